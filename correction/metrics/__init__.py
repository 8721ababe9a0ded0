"""What a wheel force is worth: the Dynamic Load Coefficient and NRMSE
(:mod:`correction.metrics.dlc`), pavement and fatigue damage (:mod:`correction.metrics.damage`,
:mod:`correction.metrics.rainflow_damage`) and spatial load profiles
(:mod:`correction.metrics.spatial_load`)."""
