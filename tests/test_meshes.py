"""gmsh meshes of the sphere: groups, arc nodes, grading, cache, failures."""

import math

import numpy as np
import pytest

from wearcheck import meshes
from wearcheck.cases import CaseError, SolverError
from wearcheck.cli import main as cli

R = 0.01


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("WEARCHECK_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def _params(n=20, rc=1.8e-4, **kw):
    return meshes.SphereMeshParameters(radius=R, contact_radius=rc, contact_edges=n, **kw)


def test_groups_and_contact_arc():
    m = meshes.sphere_mesh(_params(20))
    assert set(m.lines) == {"axis", "top", "surface", "contact"}
    assert len(m.lines["contact"]) == 20
    # every boundary node lies on its curve: arc nodes exactly on the circle
    # (gmsh places them by the circle's parametrisation; 1e-12 R round-off)
    for name in ("contact", "surface"):
        p = m.points[np.unique(m.lines[name])]
        assert np.allclose(np.hypot(p[:, 0], p[:, 1] - R), R, rtol=0, atol=1e-12 * R)
    assert np.allclose(m.points[np.unique(m.lines["axis"]), 0], 0.0)
    assert np.allclose(m.points[np.unique(m.lines["top"]), 1], R)
    # the contact arc: from the pole to rc, equal angular steps
    p = m.points[np.unique(m.lines["contact"])]
    theta = np.sort(np.arcsin(p[:, 0] / R))
    assert theta[0] == 0 and math.isclose(R * math.sin(theta[-1]), 1.8e-4, rel_tol=1e-12)
    assert np.allclose(np.diff(theta), theta[-1] / 20, rtol=1e-9)
    # the triangles cover the quarter disc: Σ areas = πR²/4 minus the chord
    # segments of the polygonal arc: relative θ²/6 for chords of angle θ;
    # the far arc has elements of R/10, θ = 0.1: 1.7e-3
    t = m.points[m.triangles]
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    area = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum() / 2
    assert abs(area / (math.pi * R**2 / 4) - 1) < 2e-3


def test_grading_keeps_the_mesh_small():
    # Sizes grow linearly with the distance from the arc, so doubling the arc
    # nodes adds elements near the arc only: far fewer than double the total.
    n1 = len(meshes.sphere_mesh(_params(50)).triangles)
    n2 = len(meshes.sphere_mesh(_params(100)).triangles)
    assert n2 < 1.8 * n1


def test_cache_hit_and_atomic_files(_cache):
    p = _params(10)
    m1 = meshes.sphere_mesh(p)
    assert m1.generate_seconds > 0 and m1.path.parent == _cache
    m2 = meshes.sphere_mesh(p)
    assert m2.generate_seconds == 0.0
    assert np.array_equal(m1.triangles, m2.triangles)
    assert sorted(f.suffix for f in _cache.iterdir()) == [".msh", ".npz"]  # no leftovers
    assert _params(11).key() != p.key() and _params(10, growth=0.3).key() != p.key()


def test_gmsh_failure_is_a_clear_error(monkeypatch):
    import gmsh

    def boom(*args, **kwargs):
        raise Exception("simulated meshing failure")

    with monkeypatch.context() as mp:
        mp.setattr(gmsh.model.mesh, "generate", boom)
        with pytest.raises(SolverError, match="gmsh failed.*simulated meshing failure"):
            meshes.sphere_mesh(_params(12))
    assert not gmsh.isInitialized()  # finalised cleanly
    assert meshes.sphere_mesh(_params(12)).generate_seconds > 0  # nothing half-cached


def test_bad_parameters():
    with pytest.raises(CaseError, match="contact arc radius"):
        meshes.sphere_mesh(_params(10, rc=2 * R))
    with pytest.raises(CaseError, match="at least one element"):
        meshes.sphere_mesh(_params(0))


def test_contact_edges_for_order():
    assert meshes.contact_edges_for(250, 1) == 249
    assert meshes.contact_edges_for(251, 2) == 125
    assert meshes.contact_edges_for(250, 2) == 125  # even: raised to 251 nodes


def test_mesh_command(tmp_path, capsys):
    from wearcheck import cases

    out = tmp_path / "m" / "paper.msh"
    rc = cli(["mesh", str(cases.shipped("paper")), "--set", "fem.contact_nodes=41",
              "--out", str(out), "--quiet"])
    text = capsys.readouterr().out
    assert rc == 0 and out.is_file()
    assert "41 contact nodes" in text and "triangles" in text
    assert cli(["mesh", str(cases.shipped("paper")), "--set", "fem.contact_nodes=3",
                "--quiet"]) == 2
    assert "fem.contact_nodes" in capsys.readouterr().err


_WRITER = """
import os, signal, sys, time
from pathlib import Path
from wearcheck import meshes
def gen(params, tmp):
    Path(tmp).write_bytes(b"half a mesh")
    if sys.argv[1] == "die":
        os.kill(os.getpid(), signal.SIGKILL)   # killed while writing the cache
    time.sleep(60)
meshes._generate = gen
meshes.sphere_mesh(meshes.SphereMeshParameters(radius=0.01, contact_radius=1.8e-4,
                                               contact_edges=int(sys.argv[2])))
"""


def test_a_killed_cache_writer_s_temporary_is_removed_a_live_one_s_kept(_cache):
    """A writer killed while gmsh writes the cache entry leaves its temporary file
    (a hidden '.sphere-<key>...msh') behind: the next write to the cache removes
    those of processes that are gone (this host), never those of a writer still at
    work (a concurrent run meshing another case)."""
    import os
    import subprocess
    import sys
    import time
    env = dict(os.environ, WEARCHECK_CACHE=str(_cache))
    # the live writer first: every writer clears dead writers' leftovers before it
    # saves, so a writer started after the kill would clear it before this test's call
    live = subprocess.Popen([sys.executable, "-c", _WRITER, "live", "12"], env=env)
    try:
        deadline = time.monotonic() + 60
        while not (_cache.is_dir() and list(_cache.iterdir())) and time.monotonic() < deadline:
            time.sleep(0.05)
        live_tmp = list(_cache.iterdir())
        assert len(live_tmp) == 1 and live_tmp[0].name.startswith(".sphere-"), live_tmp
        dead = subprocess.run([sys.executable, "-c", _WRITER, "die", "10"], env=env)
        assert dead.returncode == -9
        left = [f.name for f in _cache.iterdir() if f != live_tmp[0]]
        assert len(left) == 1 and left[0].startswith(".sphere-"), left  # the kill's leftover
        meshes.sphere_mesh(_params(10))
        names = sorted(f.name for f in _cache.iterdir())
        assert live_tmp[0].name in names and left[0] not in names, names
        assert sorted(f.suffix for f in _cache.iterdir() if f != live_tmp[0]) == [".msh", ".npz"]
    finally:
        live.kill()
        live.wait()
