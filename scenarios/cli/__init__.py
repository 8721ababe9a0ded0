"""The rigsim command line (console command ``rigsim``)."""

from scenarios.cli.main import main

__all__ = ["main"]
