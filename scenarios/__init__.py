"""rigsim's scenarios: everything that runs a scenario (core, review, studies, cli)."""

from rigsim.scenarios import scipy_import

scipy_import.install()  # before anything imports scipy.signal: see scenarios/scipy_import.py
