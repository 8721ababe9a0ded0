"""Measured data in and out: the files test labs keep (delimited text, MTS RPC III, ASAM MDF4, NI
TDMS) read into SI channels and written back (:mod:`rigsim.correction.io.measured`), the project's TOML
files (:mod:`rigsim.correction.io.tomlfile`, :mod:`rigsim.correction.io.actuator_file`) and atomic writing
(:mod:`rigsim.correction.io.atomic`)."""
