"""The explorer's upload of RGL ``.bsdf`` and ``.bin`` (UTIA or MERL) files: ``POST /api/measured/file``.

Through a real server: the answer is :func:`brdfkit.render.tables.pack` of the file read by the
Python reader (the same textures the moderngl parity tests check against the reader), a ``.bin``
told UTIA or MERL by content, the shaders served for each format compile as GLSL ES 3.00; bad
files (empty, garbage, truncated, the wrong format, the wrong suffix) are 400 with one line naming
the file by its given name, never a server path; hypothesis: any bytes and any truncation of a
valid file give an answer or a one-line ValueError, never another exception (a 500).
"""

from __future__ import annotations

import json
from urllib.parse import urlencode

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import brdfkit as bk
from brdfkit.measured.merl import write_merl_table
from brdfkit.measured.utia import tabulate_utia, write_utia_table
from brdfkit.render import glsl, tables
from brdfkit.web import api

from _web_helpers import get_json, request


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("upload")
    ward = bk.model("ward", alpha_x=0.1, alpha_y=0.4, kd=0.1)
    bk.tabulate(ward, d / "ward.bsdf", format="rgl", resolution=8, n_theta=3, n_phi=5, ndf_resolution=8)
    write_utia_table(tabulate_utia(ward), d / "ward.bin")
    table = np.random.default_rng(4).uniform(0.01, 1.0, size=(3, 90, 90, 180))  # any MERL table, written fast
    write_merl_table(table, d / "merl.bin")
    return d


def _upload(server, name, data):
    return request(server, "/api/measured/file?" + urlencode({"name": name}), data)


@pytest.mark.parametrize("name,fmt", [("ward.bsdf", "rgl"), ("ward.bin", "utia"), ("merl.bin", "merl")])
def test_upload_sends_the_readers_tables(server, files, name, fmt):
    path = files / name
    status, ctype, data = _upload(server, "my " + name, path.read_bytes())
    assert status == 200 and ctype == "application/octet-stream"
    head, arrays = tables.unpack(data)
    assert head["format"] == fmt and head["name"] == "my " + name
    assert head["shader"] == {"rgl": "rgl.glsl", "utia": "utia.glsl", "merl": "measured.glsl"}[fmt]
    m = bk.model(str(path))
    if fmt == "merl":
        assert np.array_equal(arrays[0], glsl.table_texels(m)) and head["ints"] == {"u_interpolation": 0}
        return
    ref = tables.table_set(m)
    assert head["ints"] == ref.ints and head["isotropic"] is False
    assert [r["uniform"] for r in head["textures"]] == [t.uniform for t in ref.textures]
    assert [r["unit"] for r in head["textures"]] == list(range(tables.FIRST_UNIT, tables.FIRST_UNIT + len(arrays)))
    for got, t in zip(arrays, ref.textures):
        assert np.array_equal(got, t.data)


@pytest.mark.parametrize("fmt", ["rgl", "utia", "merl"])
def test_the_shader_of_each_format(server, fmt):
    status, ctype, text = request(server, f"/api/measured/shader?format={fmt}")
    assert status == 200 and ctype.startswith("text/plain")
    text = text.decode()
    assert text.startswith("#version 300 es\n") and "vec3 brdf(vec3 wi, vec3 wo)" in text
    glsl.compile_source(text[len("#version 300 es\n"):], "300 es")
    status, body = get_json(server, "/api/measured/shader?format=nope")
    assert status == 400 and "unknown table format" in body["error"]


def _bad_files(files):
    good = (files / "ward.bsdf").read_bytes()
    return [
        ("x.bsdf", b"", "empty"),
        ("garbage.bsdf", b"\x00" * 100, "garbage.bsdf"),
        ("half.bsdf", good[: len(good) // 2], "half.bsdf"),
        ("merl-named.bsdf", (files / "merl.bin").read_bytes()[:5000], "merl-named.bsdf"),
        ("short.bin", b"\x00" * 1000, "short.bin"),
        ("notes.txt", b"hello", "expected an RGL .bsdf or a UTIA/MERL .bin"),
        ("../../etc/evil.bsdf", b"\x01\x02", "evil.bsdf"),
    ]


def test_bad_files_are_400_with_one_line(server, files):
    for name, data, needle in _bad_files(files):
        status, ctype, raw = _upload(server, name, data)
        body = json.loads(raw)
        assert status == 400, (name, status, body)
        err = body["error"]
        assert needle in err and "\n" not in err and "/tmp" not in err and "brdfkit-web" not in err, (name, err)
        assert "../" not in err


def _ok_or_one_line(name, data):
    try:
        api.measured_file_upload({"name": [name]}, data)
    except ValueError as e:
        msg = str(e)
        assert "\n" not in msg and "/tmp" not in msg and "brdfkit-web" not in msg, msg


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(min_size=1, max_size=600), suffix=st.sampled_from([".bsdf", ".bin"]))
def test_any_bytes_give_an_answer_or_one_line(data, suffix):
    _ok_or_one_line("f" + suffix, data)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cut=st.floats(0.0, 1.0), flip=st.integers(0, 10**9))
def test_any_damaged_bsdf_gives_an_answer_or_one_line(files, cut, flip):
    good = bytearray((files / "ward.bsdf").read_bytes())
    good[flip % len(good)] ^= 0xFF  # one byte flipped anywhere (header, offsets, values)
    _ok_or_one_line("damaged.bsdf", bytes(good[: max(1, int(cut * len(good)))]))
