"""Output correction: the actuator transfer function T_a (the paper's eq. 4,
:mod:`correction.output.transfer`), the low-pass T_F (:mod:`correction.output.lowpass`), the
correction filter T_a^-1 T_F designed as SOS (:mod:`correction.output.filters`), applied to
measured forces (:mod:`correction.output.apply`, :mod:`correction.output.pipeline`), the
linear floor of any such correction (:mod:`correction.output.floor`), and a record's white noise
taken out where it outweighs its signal (:mod:`correction.output.denoise`, through
:mod:`correction.output.spectral`)."""
