"""Correcting the dynamic wheel forces measured on road simulators, with no simulator.

=================  =============================================================================
subpackage         what it holds
=================  =============================================================================
``io``             measured data in and out (CSV, RPC III, MDF4, TDMS), TOML and actuator files
``identification`` frequency responses, the actuator transfer function T_a fitted on rig data
``output``         eq. 4, the low-pass, the correction filter T_a^-1 T_F and its application
``input``          drive-file iteration (input correction)
``metrics``        DLC, NRMSE, pavement and fatigue damage, spatial load profiles
=================  =============================================================================
"""
