"""The rigsim command line: ``main`` in :mod:`scenarios.cli.main` (console command ``rigsim``)."""
