"""Correcting a rig's records: the floor between the simulated rig (:mod:`scenarios.core`) and the
studies. What ``rigsim correct`` and ``rigsim identify --from-file`` run, and what a lab's own
script calls: which channels of a record are corrected (:mod:`scenarios.records.channels`), the
identification of T_a from a recorded file (:mod:`scenarios.records.recorded`), the correction by
a truck model calibrated on the record (:mod:`scenarios.records.model`) and the corrected file
written (:mod:`scenarios.records.output`).
"""
