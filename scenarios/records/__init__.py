"""Correcting a rig's records: the floor between the simulated rig (:mod:`rigsim.scenarios.core`) and the
studies. What ``rigsim correct`` and ``rigsim identify --from-file`` run, and what a lab's own
script calls (:mod:`rigsim.scenarios.records.api`)::

    import rigsim
    record = rigsim.read_record("rig.csv")
    result = rigsim.correct_record(record, rigsim.LinearOptions(actuators="acts.toml"))
    result.write("corrected.rsp")

Inside: the options checked and their files read (:mod:`rigsim.scenarios.records.settings`), which
channels of a record are corrected (:mod:`rigsim.scenarios.records.channels`), the correction planned
and run (:mod:`rigsim.scenarios.records.plan`; linear: :mod:`rigsim.scenarios.records.linear`, by a truck model
calibrated on the record: :mod:`rigsim.scenarios.records.model_record` and
:mod:`rigsim.scenarios.records.model`), the identification of T_a from a recorded file
(:mod:`rigsim.scenarios.records.recorded`), the result and its file (:mod:`rigsim.scenarios.records.corrected`,
:mod:`rigsim.scenarios.records.output`). Imports nothing heavy: a command's parser imports the package.
"""

from rigsim.scenarios.records.api import (ChannelLoads, CorrectionResult, LinearOptions, ModelOptions, correct_record,
                                          identify_record, read_record)

__all__ = ["read_record", "correct_record", "identify_record", "LinearOptions", "ModelOptions", "CorrectionResult",
           "ChannelLoads"]
