"""Measured data in and out: the files test labs keep (delimited text, MTS RPC III, ASAM MDF4, NI
TDMS) read into SI channels and written back (:mod:`correction.io.measured`), the project's TOML
files (:mod:`correction.io.tomlfile`, :mod:`correction.io.actuator_file`) and atomic writing
(:mod:`correction.io.atomic`)."""
