"""The rigsim command line: ``main`` in :mod:`rigsim.scenarios.cli.main` (console command ``rigsim``)."""
