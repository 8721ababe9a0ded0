"""Identification of the rig from measured records: frequency-response estimates
(:mod:`rigsim.correction.identification.identify`), the one fit of the actuator transfer function T_a
(:mod:`rigsim.correction.identification.actuator_fit`) and the measurement noise of a record
(:mod:`rigsim.correction.identification.noise`)."""
