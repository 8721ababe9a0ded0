"""Output correction: the actuator transfer function T_a (the paper's eq. 4,
:mod:`rigsim.correction.output.transfer`), the low-pass T_F (:mod:`rigsim.correction.output.lowpass`), the
correction filter T_a^-1 T_F designed as SOS (:mod:`rigsim.correction.output.filters`), applied to
measured forces (:mod:`rigsim.correction.output.apply`, :mod:`rigsim.correction.output.pipeline`), the
linear floor of any such correction (:mod:`rigsim.correction.output.floor`), and a record's white noise
taken out where it outweighs its signal (:mod:`rigsim.correction.output.denoise`, through
:mod:`rigsim.correction.output.spectral`)."""
