"""Identification of the rig from measured records: frequency-response estimates
(:mod:`correction.identification.identify`), the one fit of the actuator transfer function T_a
(:mod:`correction.identification.actuator_fit`) and the measurement noise of a record
(:mod:`correction.identification.noise`)."""
