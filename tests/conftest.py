"""Fixtures shared by the tests of every package."""

from __future__ import annotations

import pytest


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.fixture()
def one_line():
    """``one_line(stderr) -> str``: the one line a refused command prints, asserting it is one line
    and no traceback."""
    return _one_line
