"""Input correction: drive files iterated on the rig until the response matches a target
(:mod:`rigsim.correction.input.iterate`), with measured frequency-response matrices
(:mod:`rigsim.correction.input.frf`), the drive update (:mod:`rigsim.correction.input.update`) and its
convergence (:mod:`rigsim.correction.input.convergence`)."""
