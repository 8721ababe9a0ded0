"""Import scipy.signal without re-parsing ~800 docstrings: 0.7 s off every process's start.

SciPy 1.17's ``xp_capabilities`` decorator (``scipy._lib._array_api``) parses the docstring of
every function it decorates with ``FunctionDoc`` when ``scipy.signal`` is imported, to append a
note on array-API backends: measured here, 0.7 of the 0.79 s that ``import scipy.signal`` takes,
in every rigsim process (the command and each worker), a third of a short run's fixed cost.

:func:`install` adds an import hook that, when ``scipy._lib._array_api`` is loaded, replaces the
``FunctionDoc`` it uses by :class:`_KeepDoc`, which leaves each docstring as it is (without that
note). Nothing else of SciPy changes: the functions are the same objects. The hook does nothing
when the module has no ``FunctionDoc`` (other SciPy versions), when SciPy was imported before
rigsim, or when ``RIGSIM_SCIPY_DOCS=1`` is set (full docstrings, as SciPy makes them).
"""

from __future__ import annotations

import importlib.abc
import os
import sys

__all__ = ["install", "TARGET"]

#: The module whose docstring parser is replaced.
TARGET = "scipy._lib._array_api"


class _KeepDoc:
    """Stands in for ``FunctionDoc`` in ``xp_capabilities``: the decorator appends to
    ``doc['Notes']`` and then keeps ``str(doc)`` after its first line (the signature)."""

    def __init__(self, func) -> None:
        self._doc = getattr(func, "__doc__", None) or ""
        self._sections: dict[str, list] = {}

    def __getitem__(self, key: str) -> list:
        return self._sections.setdefault(key, [])

    def __str__(self) -> str:
        return "\n" + self._doc


class _Loader(importlib.abc.Loader):
    def __init__(self, loader) -> None:
        self.loader = loader

    def create_module(self, spec):
        return self.loader.create_module(spec)

    def exec_module(self, module) -> None:
        self.loader.exec_module(module)
        if hasattr(module, "FunctionDoc"):
            module.FunctionDoc = _KeepDoc


class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name != TARGET:
            return None
        import importlib.util

        sys.meta_path.remove(self)  # once; let the normal finders locate it
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.loader is not None:
            spec.loader = _Loader(spec.loader)
        return spec


def install() -> bool:
    """Install the hook (once per process); returns whether it is active."""
    if os.environ.get("RIGSIM_SCIPY_DOCS") == "1" or TARGET in sys.modules:
        return False
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
    return True
