"""Input correction: drive files iterated on the rig until the response matches a target
(:mod:`correction.input.iterate`), with measured frequency-response matrices
(:mod:`correction.input.frf`), the drive update (:mod:`correction.input.update`) and its
convergence (:mod:`correction.input.convergence`)."""
