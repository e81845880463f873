"""The atomic writer and the output-path check every command uses (brdfkit.fileio)."""

import os
import signal
import subprocess
import sys
import time

import pytest

from brdfkit import fileio


def test_atomic_open_replaces_whole(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("old")
    with fileio.atomic_open(p, "w") as f:
        f.write("new")
        assert p.read_text() == "old"  # not visible until the block ends
    assert p.read_text() == "new"
    assert sorted(os.listdir(tmp_path)) == ["a.txt"]


def test_atomic_open_exception_keeps_previous(tmp_path):
    p = tmp_path / "a.bin"
    p.write_bytes(b"previous")
    with pytest.raises(RuntimeError):
        with fileio.atomic_open(p, "wb") as f:
            f.write(b"partial")
            raise RuntimeError("boom")
    assert p.read_bytes() == b"previous"
    assert sorted(os.listdir(tmp_path)) == ["a.bin"]


def test_atomic_path_keeps_suffix(tmp_path):
    p = tmp_path / "img.png"
    with fileio.atomic_path(p) as tmp:
        assert tmp.endswith(".png") and os.path.dirname(tmp) == str(tmp_path)
        with open(tmp, "wb") as f:
            f.write(b"x")
    assert p.read_bytes() == b"x"


def test_write_json_and_mode(tmp_path):
    p = tmp_path / "x.json"
    fileio.write_json(p, {"a": 1})
    assert p.read_text() == '{\n  "a": 1\n}\n'
    umask = os.umask(0)
    os.umask(umask)
    assert (p.stat().st_mode & 0o777) == (0o666 & ~umask)
    with pytest.raises(ValueError):
        with fileio.atomic_open(p, "a"):
            pass


def test_kill_9_mid_write_keeps_previous_file(tmp_path):
    p = tmp_path / "big.bin"
    p.write_bytes(b"A" * 1000)
    code = (
        "import sys, time\n"
        "from brdfkit import fileio\n"
        "with fileio.atomic_open(sys.argv[1], 'wb') as f:\n"
        "    f.write(b'B' * 100000); f.flush(); print('writing', flush=True); time.sleep(60)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code, str(p)], stdout=subprocess.PIPE)
    assert proc.stdout.readline().strip() == b"writing"
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    assert p.read_bytes() == b"A" * 1000


def test_check_output_path(tmp_path):
    ok = fileio.check_output_path(tmp_path / "x.png", suffixes=(".png", ".exr"))
    assert ok == tmp_path / "x.png"
    made = []
    fileio.check_output_path(tmp_path / "new" / "x.png", notify=made.append)
    assert (tmp_path / "new").is_dir() and len(made) == 1 and "new" in made[0]
    with pytest.raises(ValueError, match="does not exist"):
        fileio.check_output_path(tmp_path / "a" / "b" / "x.png")
    assert not (tmp_path / "a").exists()
    with pytest.raises(ValueError, match="must end in"):
        fileio.check_output_path(tmp_path / "x.jpg", suffixes=(".png",))
    with pytest.raises(ValueError, match="is a folder"):
        fileio.check_output_path(tmp_path)
    (tmp_path / "afile").write_text("")
    with pytest.raises(ValueError, match="not a folder"):
        fileio.check_output_path(tmp_path / "afile" / "t.png")
    d = fileio.check_output_path(tmp_path / "outdir", is_dir=True)
    assert d.is_dir()
