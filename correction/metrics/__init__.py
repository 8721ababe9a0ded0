"""What a wheel force is worth: the Dynamic Load Coefficient and NRMSE
(:mod:`rigsim.correction.metrics.dlc`), pavement and fatigue damage (:mod:`rigsim.correction.metrics.damage`,
:mod:`rigsim.correction.metrics.rainflow_damage`) and spatial load profiles
(:mod:`rigsim.correction.metrics.spatial_load`)."""
