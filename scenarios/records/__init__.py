"""Correcting a rig's records: the floor between the simulated rig (:mod:`scenarios.core`) and the
studies. What ``rigsim correct`` and ``rigsim identify --from-file`` run, and what a lab's own
script calls (:mod:`scenarios.records.api`)::

    from scenarios.records import read_record, correct_record
    record = read_record("rig.csv")
    result = correct_record(record, actuators="acts.toml")
    result.write("corrected.rsp")

Inside: the options checked and their files read (:mod:`scenarios.records.settings`), which
channels of a record are corrected (:mod:`scenarios.records.channels`), the correction planned
and run (:mod:`scenarios.records.plan`; linear: :mod:`scenarios.records.linear`, by a truck model
calibrated on the record: :mod:`scenarios.records.model_record` and
:mod:`scenarios.records.model`), the identification of T_a from a recorded file
(:mod:`scenarios.records.recorded`), the result and its file (:mod:`scenarios.records.corrected`,
:mod:`scenarios.records.output`). Imports nothing heavy: a command's parser imports the package.
"""

from scenarios.records.api import ChannelLoads, CorrectionResult, correct_record, identify_record, read_record

__all__ = ["read_record", "correct_record", "identify_record", "CorrectionResult", "ChannelLoads"]
