"""Test-session settings shared by every module.

Hypothesis draws its examples from a seed fixed per test (``derandomize``), so every run of the
suite tests the same cases and a failure in CI reproduces on a developer's machine; set
``BRDFKIT_FUZZ=1`` for randomised runs (new examples each time), which is how new cases are found.
Tests that set ``max_examples`` or ``deadline`` themselves inherit the rest from this profile.

The ``server`` fixture (a live explorer server) serves the test_web_* modules; ``mi`` (Mitsuba 3)
the modules that compare with Mitsuba; ``cli`` runs ``brdfkit ARGS...`` in-process.
"""

from __future__ import annotations

import os
from typing import NamedTuple

import pytest
from hypothesis import settings

FUZZ = os.environ.get("BRDFKIT_FUZZ", "") not in ("", "0")

settings.register_profile("brdfkit-ci", derandomize=True, database=None)
settings.register_profile("brdfkit-fuzz", derandomize=False)
settings.load_profile("brdfkit-fuzz" if FUZZ else "brdfkit-ci")


@pytest.fixture(scope="module")
def server():
    """A live explorer server on 127.0.0.1 (port 0) in a thread, one per test module; shut down afterwards."""
    from brdfkit.web import start_in_thread

    srv, thread = start_in_thread("127.0.0.1", 0)
    yield srv
    srv.shutdown()
    srv.server_close()
    thread.join(5)


@pytest.fixture(scope="module")
def mi():
    """The mitsuba module in its ``scalar_rgb`` variant (skips where Mitsuba 3 is not installed)."""
    mitsuba = pytest.importorskip("mitsuba")
    mitsuba.set_variant("scalar_rgb")
    return mitsuba


class CliRun(NamedTuple):
    """What an in-process ``brdfkit`` run gave: unpacks as ``rc, out, err``."""

    returncode: int
    stdout: str
    stderr: str


@pytest.fixture
def cli(capsys):
    """``brdfkit ARGS...`` in-process (brdfkit.cli.main): a :class:`CliRun`. The subprocess path is
    tested in test_measured_merl."""
    from brdfkit.cli import main

    def run(*args):
        capsys.readouterr()
        rc = main(list(args))
        out = capsys.readouterr()
        return CliRun(rc, out.out, out.err)

    return run
