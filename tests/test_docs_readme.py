"""The README works as written, from any folder (issue 30).

Every shell command of the README (a line of a ```bash or ```console block that starts with
``brdfkit``, after the console's ``$ ``) runs from a temporary folder outside the repository,
writing there, and exits 0. ``brdfkit`` and ``python`` are this interpreter (``python -m
brdfkit``), so the test runs the source under test, installed or not.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"

#: commands not run as written, and why (each must still be in the README: see the last test)
SKIPPED = {
    "brdfkit serve": "starts a server that runs until stopped (tests/test_web_*.py start it)",
    "brdfkit gallery": "renders nine sheets, minutes of CPU: run below with --only materials --size 48",
    "brdfkit measure ggx -p alpha=0.5 -o traced.bsdf": "traces 4.8 million paths: run below with fewer",
}

#: what runs instead of a skipped command, where something can
SUBSTITUTES = {
    "brdfkit gallery": "brdfkit gallery --only materials --size 48",
    "brdfkit measure ggx -p alpha=0.5 -o traced.bsdf":
        "brdfkit measure ggx -p alpha=0.5 -o traced.bsdf --samples 2000 --n-theta 3",
}


def readme_commands(text: str) -> list[str]:
    """The ``brdfkit`` command lines of the README's bash and console blocks, comments removed."""
    out = []
    for lang, block in re.findall(r"(?ms)^```(bash|console)\n(.*?)^```", text):
        for line in block.splitlines():
            line = line.strip()
            if lang == "console":
                if not line.startswith("$ "):
                    continue
                line = line[2:]
            if not line.startswith("brdfkit"):
                continue
            out.append(_strip_comment(line))
    return out


def _strip_comment(line: str) -> str:
    """``line`` without a trailing ``  # comment`` (the README's commands put no ``#`` elsewhere)."""
    return re.split(r"\s+#\s", line, maxsplit=1)[0].rstrip()


def _shims(folder: Path) -> dict[str, str]:
    """An environment whose ``brdfkit`` and ``python`` are this interpreter."""
    folder.mkdir()
    for name, cmd in (("brdfkit", f'exec "{sys.executable}" -m brdfkit "$@"'), ("python", f'exec "{sys.executable}" "$@"')):
        p = folder / name
        p.write_text(f"#!/bin/sh\n{cmd}\n")
        p.chmod(0o755)
    env = dict(os.environ)
    env["PATH"] = f"{folder}{os.pathsep}{env.get('PATH', '')}"
    src = str(ROOT / "src")
    env["PYTHONPATH"] = src + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


COMMANDS = readme_commands(README.read_text())


def test_the_readme_has_commands_and_the_test_command():
    assert len(COMMANDS) >= 10
    assert "brdfkit gallery" in COMMANDS  # the main command
    # .ci/run runs "the exact test command that the README gives"
    assert "```bash\npython -m pytest -n 2 -q\n```" in README.read_text()
    assert "python -m pytest -n 2 -q" in (ROOT / ".ci" / "run").read_text()
    for skipped in SKIPPED:
        assert skipped in COMMANDS, f"SKIPPED names {skipped!r}, which the README no longer gives"


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted(set(COMMANDS)))
def test_readme_command_runs_from_any_folder(command, tmp_path):
    if command in SKIPPED and command not in SUBSTITUTES:
        pytest.skip(SKIPPED[command])
    if command.startswith("brdfkit measure "):
        from brdfkit.microsurfaces import available

        if not available("mitsuba-llvm"):
            pytest.skip("brdfkit measure traces with Mitsuba 3's llvm variant, not available here")
    run = SUBSTITUTES.get(command, command)
    work = tmp_path / "work"
    work.mkdir()
    env = _shims(tmp_path / "bin")
    r = subprocess.run(["bash", "-c", run], cwd=work, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, f"{run!r} exited {r.returncode}:\n{r.stderr[-2000:]}"
    assert "Traceback" not in r.stderr
    for out in re.findall(r"-o (\S+)", run):
        assert (work / out).exists(), f"{run!r} did not write {out} in its working folder"


@pytest.mark.slow
def test_readme_python_block_runs_from_any_folder(tmp_path):
    """The README's Python example, run as a script in a temporary folder (it writes files there)."""
    code = re.search(r"(?ms)^```python\n(.*?)^```", README.read_text()).group(1)
    (tmp_path / "example.py").write_text(code + "\nprint(sorted(m.params), r.error > 0)\n")
    env = _shims(tmp_path / "bin")
    r = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert (tmp_path / "ct.binary").is_file() and (tmp_path / "ward.glb").is_file()
