"""``python -m rigsim``: the ``rigsim`` command (:func:`rigsim.scenarios.cli.main.main`)."""

from rigsim.scenarios.cli.main import main

raise SystemExit(main())
