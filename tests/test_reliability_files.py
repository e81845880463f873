"""No lost file: ``kill -9`` during every writer leaves the previous file whole (issue 14).

Each case runs the real writer in a child process beside a watcher thread that
sends the process SIGKILL the moment writing starts -- a temporary file
appears in the folder, or the destination itself changes (what the old
in-place writers did: they truncated the user's file first). The destination
must then hold exactly its previous bytes. If the writer finishes before the
watcher fires (it never did here, the files are tens of MB), the attempt is
repeated; the new file must then be whole.

The fit report and batch writers (``measured/``, the fitting branch) and the
gallery (``render/gallery.py``, the image-based-lighting branch) go through the
same :mod:`brdfkit.fileio` calls in those branches.

Also: output paths are checked before the work starts (``check --all --plot
afile/t.png`` fails at once, ``render -o /nonexistent/dir/x.png`` creates
nothing), and at most one missing folder level is created, with a note.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from brdfkit.cli import main

SRC = str(Path(__file__).resolve().parents[1] / "src")

WATCH = r"""
import os, signal, sys, threading, time
dest = sys.argv[1]
folder, base = os.path.split(dest)
st0 = os.stat(dest)
start = threading.Event()
def watch():
    start.wait()
    while True:
        try:
            names = os.listdir(folder)
        except OSError:
            names = []
        if any(n.startswith("." + base + ".") for n in names):
            os.kill(os.getpid(), signal.SIGKILL)
        try:
            st = os.stat(dest)
            changed = (st.st_size, st.st_mtime_ns, st.st_ino) != (st0.st_size, st0.st_mtime_ns, st0.st_ino)
        except FileNotFoundError:
            changed = True
        if changed:
            os.kill(os.getpid(), signal.SIGKILL)
        time.sleep(0.0002)
threading.Thread(target=watch, daemon=True).start()
"""

# Each writer: (file name, code that prepares `data` (not timed), code that writes it to `dest`).
WRITERS = {
    "png": (
        "out.png",
        "rng = np.random.default_rng(1); disp = rng.random((3000, 3000, 4)); disp[..., 3] = 1",
        "from brdfkit.render.image import save_image; save_image(dest, disp, disp)",
    ),
    "exr": (
        "out.exr",
        "rng = np.random.default_rng(2); lin = rng.random((2048, 2048, 4)).astype(np.float32)",
        "from brdfkit.render.image import save_image; save_image(dest, lin, lin)",
    ),
    "npy": (
        "out.npy",
        "rng = np.random.default_rng(3); lin = rng.random((3000, 3000, 4)).astype(np.float32)",
        "from brdfkit.render.image import save_image; save_image(dest, lin, lin)",
    ),
    "merl": (
        "out.binary",
        "rng = np.random.default_rng(4); table = rng.random((3, 90, 90, 180))",
        "from brdfkit.measured.merl import write_merl_table; write_merl_table(table, dest)",
    ),
    "plot": (
        "out.png",
        "import matplotlib; matplotlib.use('Agg'); import matplotlib.pyplot as plt\n"
        "fig, ax = plt.subplots(figsize=(30, 30)); rng = np.random.default_rng(5)\n"
        "ax.imshow(rng.random((1500, 1500)), interpolation='nearest')",
        "from brdfkit.analysis.plots import save_figure; save_figure(fig, dest, dpi=100)",
    ),
    "json": (
        "out.json",
        "obj = {'values': np.random.default_rng(6).random(1_500_000).tolist()}",
        "from brdfkit.fileio import write_json; write_json(dest, obj)",
    ),
    "csv": (  # a CSV table written line by line through atomic_open (as the fit batch tables are)
        "fit_errors.csv",
        "rows = ['m%d,' % i + ','.join(['0.123456'] * 400) for i in range(20000)]",
        "from brdfkit.fileio import atomic_open\n"
        "with atomic_open(dest, 'w') as fh:\n"
        "    for r in rows: fh.write(r + '\\n')",
    ),
}


def _run_killed(tmp_path: Path, name: str, prepare: str, write: str) -> tuple[int, bytes, bytes]:
    dest = tmp_path / name
    script = (
        "import numpy as np\n"
        + prepare
        + "\n"
        + WATCH
        + "\nstart.set()\n"
        + "dest = sys.argv[1]\n"
        + write
        + "\nprint('finished')\n"
    )
    env = dict(os.environ, PYTHONPATH=SRC)
    r = subprocess.run([sys.executable, "-c", script, str(dest)], capture_output=True, env=env, timeout=300)
    return r.returncode, r.stdout, r.stderr


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_kill_9_during_write_keeps_the_previous_file(tmp_path, writer):
    name, prepare, write = WRITERS[writer]
    dest = tmp_path / name
    previous = b"the user's previous file, which must survive\n" * 1000
    killed = False
    for _attempt in range(3):
        dest.write_bytes(previous)
        rc, out, err = _run_killed(tmp_path, name, prepare, write)
        if rc == -signal.SIGKILL:
            killed = True
            assert dest.read_bytes() == previous, f"{writer}: previous file damaged ({dest.stat().st_size} bytes)"
            break
        assert rc == 0, err.decode()[-2000:]
        assert dest.stat().st_size > 0 and dest.read_bytes() != previous  # finished first: a whole new file
    assert killed, f"{writer}: the watcher never caught the write in progress"


def test_interrupted_write_in_process_keeps_the_previous_file(tmp_path):
    """An exception inside the writer (Ctrl-C, disk full) removes the temporary file and keeps the old one."""
    from brdfkit.render import image

    dest = tmp_path / "x.png"
    dest.write_bytes(b"old")

    class Boom(Exception):
        pass

    def bad_fromarray(*a, **k):
        raise Boom()

    from PIL import Image

    orig = Image.fromarray
    Image.fromarray = bad_fromarray
    try:
        with pytest.raises(Boom):
            image.save_png(dest, np.zeros((4, 4, 4)))
    finally:
        Image.fromarray = orig
    assert dest.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.png"]


def test_writers_produce_readable_files(tmp_path):
    from brdfkit.measured.merl import read_merl_table, write_merl_table
    from brdfkit.render.image import read_exr, save_image

    lin = np.random.default_rng(0).random((8, 6, 4)).astype(np.float32)
    for suffix in (".png", ".exr", ".npy"):
        save_image(tmp_path / f"a{suffix}", lin, lin)
    assert np.array_equal(np.load(tmp_path / "a.npy"), lin)
    assert np.array_equal(read_exr(tmp_path / "a.exr"), lin)
    from PIL import Image

    assert Image.open(tmp_path / "a.png").size == (6, 8)
    table = np.full((3, 90, 90, 180), 0.25)
    write_merl_table(table, tmp_path / "t.binary")
    assert np.allclose(read_merl_table(tmp_path / "t.binary"), 0.25)
    # files get normal permissions, not mkstemp's 0600
    mode = (tmp_path / "a.png").stat().st_mode & 0o777
    umask = os.umask(0)
    os.umask(umask)
    assert mode == 0o666 & ~umask


# --------------------------------------------------------------------------- paths checked first
def test_check_all_plot_into_a_file_fails_before_any_work(tmp_path, capsys, monkeypatch):
    (tmp_path / "afile").write_text("x")
    import brdfkit.analysis.commands as cmds

    def no_work(*a, **k):
        raise AssertionError("the checks ran before the output path was validated")

    monkeypatch.setattr(cmds, "_run_all", no_work)
    rc = main(["check", "--all", "--plot", str(tmp_path / "afile" / "t.png")])
    err = capsys.readouterr().err
    assert rc == 2 and "not a folder" in err, err


def test_render_into_a_missing_tree_creates_nothing(tmp_path, capsys):
    target = tmp_path / "nonexistent" / "dir" / "x.png"
    t0 = time.perf_counter()
    rc = main(["render", "-o", str(target), "--mesh", "sphere", "--size", "16x16", "--backend", "numpy"])
    err = capsys.readouterr().err
    assert rc == 2 and "does not exist" in err, err
    assert not (tmp_path / "nonexistent").exists()


def test_one_missing_level_is_created_and_said(tmp_path, capsys):
    target = tmp_path / "new" / "x.png"
    rc = main(["plot", "lambert", "--kind", "polar", "-o", str(target)])
    err = capsys.readouterr().err
    assert rc == 0, err
    assert target.is_file() and "created folder" in err


@pytest.mark.parametrize(
    "argv",
    [
        ["plot", "lambert", "-o", "{tmp}/afile/p.png"],
        ["plot", "lambert", "-o", "{tmp}/a/b/p.png"],
        ["plot", "lambert", "-o", "{tmp}/p.jpg"],
        ["gallery", "-o", "{tmp}/afile", "--only", "materials"],
        ["gallery", "-o", "{tmp}/a/b/c"],
    ],
)
def test_every_writing_command_checks_its_path_first(tmp_path, capsys, argv):
    (tmp_path / "afile").write_text("x")
    args = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    rc = main(args)
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("brdfkit: error:"), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_save_merl_checks_the_path_before_tabulating(tmp_path, monkeypatch):
    import brdfkit as bk
    from brdfkit.measured import merl

    monkeypatch.setattr(merl, "tabulate", lambda m: (_ for _ in ()).throw(AssertionError("tabulated first")))
    with pytest.raises(ValueError, match="does not exist"):
        bk.save_merl(bk.model("lambert"), tmp_path / "x" / "y" / "z.binary")


def test_a_bad_argument_creates_no_folder(tmp_path, capsys):
    """Cheap argument checks come before the output check, which may create a folder level."""
    bad_scene = tmp_path / "bad.json"
    bad_scene.write_text('{"size": [0, 5]}')
    cases = [
        ["render", "--scene", str(bad_scene), "-o", "{tmp}/new/x.png"],
        ["plot", "no-such-model", "-o", "{tmp}/new/p.png"],
        ["gallery", "--only", "no-such-figure", "-o", "{tmp}/new"],
    ]
    for argv in cases:
        rc = main([a.replace("{tmp}", str(tmp_path)) for a in argv])
        err = capsys.readouterr().err
        assert rc == 2 and "created folder" not in err, err
        assert not (tmp_path / "new").exists(), argv
