"""Shared pieces of the Python module's tests: a small coupled scene (the paper's cup, coarse),
the CLI, and a reader of the CLI's PLY frames."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import sphfem

SOURCE = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture
def cup():
    """The paper's cup scene as a dict, coarse: 9 mm particles, a cup of a few hundred tets."""
    s = sphfem.load_scene(SOURCE / "scenes/paper/cup.json")
    s["fluid"]["particle_radius"] = 0.009
    s["fluid"]["max_particles"] = 4000
    s["bodies"][0]["resolution"] = 5
    return s


@pytest.fixture
def cup_file(cup, tmp_path):
    path = tmp_path / "cup.json"
    path.write_text(json.dumps(cup))
    return path


def cli(*args):
    """Runs the sphfem command; returns (exit code, stdout + stderr)."""
    exe = os.environ.get("SPHFEM_CLI", "sphfem")
    r = subprocess.run([exe, *map(str, args)], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


def read_ply(path):
    """A binary little-endian PLY point frame as a structured array (write_ply's layout)."""
    data = pathlib.Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    fields, n = [], 0
    for line in data[:end].decode().splitlines():
        words = line.split()
        if words[:2] == ["element", "vertex"]:
            n = int(words[2])
        elif words[0] == "property":
            fields.append((words[2], "<f4" if words[1] == "float" else "<i4"))
    return np.frombuffer(data, dtype=np.dtype(fields), count=n, offset=end)
