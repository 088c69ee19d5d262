"""``wearcheck verify``: results produced elsewhere judged against the certified reference.

The right results are an independent run of the paper case (MDR at N = 400, the
shipped time tolerance: nothing in common with the reference but the method;
and the FEM, a different method) handed over in every format; the wrong ones are
the same results at 1.05 times the sliding distance (a wear coefficient 1/1.05
of the case's: 4.8 % too low). The verdict must pass the first and fail the second, naming the stage and
the quantity. Tolerances are the case's [compare] keys, unchanged.
"""

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

import wearcheck
from wearcheck.cases import CaseError
from wearcheck import external

import verify_formats as fmt


@pytest.fixture
def no_figures(monkeypatch):
    """The verdict without its figures (matplotlib's PNG and PDF take most of a verify's
    time); test_output_directory draws them."""
    from wearcheck.comparisons.present import verify_figures
    monkeypatch.setattr(verify_figures, "draw", lambda *a, **k: [])


@pytest.fixture(scope="module")
def paper_run():
    # the paper case as another code would compute it: coarser, the shipped tolerance
    return wearcheck.solve(wearcheck.load_case("paper", {"mdr.elements": 400}), "mdr")


def run_verify(case, results, out, mapping=(), **kw):
    return wearcheck.verify(case, results, out, mapping=list(mapping), **kw)


def failed_stages(m):
    """{stage index: [failed check columns]}"""
    out = {}
    for st in m["pairs"]["results"]["stages"]:
        bad = [c for c, v in st["checks"].items() if not v["passed"]]
        if bad:
            out[st["index"]] = bad
    return out


FORMATS = {
    "csv": (lambda d, run, scale: fmt.csv_dir(d / "res", run, scale=scale), ()),
    "csv-s_hat": (lambda d, run, scale: fmt.csv_dir(d / "res", run, scale=scale,
                                                    time="s_hat"), ()),
    "fe-export": (lambda d, run, scale: fmt.fe_export(d / "res", run, scale=scale),
                  fmt.FE_EXPORT_MAP),
    "vtk": (lambda d, run, scale: fmt.vtk_series(d / "res", run, scale=scale), fmt.VTK_MAP),
    "calculix": (lambda d, run, scale: fmt.calculix(d / "res", run, scale=scale),
                 fmt.CALCULIX_MAP),
}


@pytest.mark.parametrize("name", list(FORMATS))
def test_right_results_pass_and_k_five_percent_off_fails(no_figures, tmp_path, paper_run, name):
    write, mapping = FORMATS[name]
    good = write(tmp_path / "good", paper_run, 1.0)
    m = run_verify("paper", good, tmp_path / "v-good", mapping)
    assert m["passed"], json.dumps(failed_stages(m))
    judged = m["pairs"]["results"]["stages"]
    assert len(judged) == 7                       # the seven stages of paper.toml
    bad = write(tmp_path / "bad", paper_run, 1.05)
    m = run_verify("paper", bad, tmp_path / "v-bad", mapping)
    assert not m["passed"]
    failed = failed_stages(m)
    # every stage after the start slides 5 % too far: the late stages' force and
    # pressure are off by far more than their 3 % (the force falls ~exponentially)
    last = max(failed)
    assert last == len(judged) - 1
    assert {"pressure_interior_max"} <= set(failed[last])
    if name != "vtk":                             # the VTK series carries no force
        assert "force" in failed[last]
    report = (tmp_path / "v-bad" / "report.md").read_text()
    assert f"stage {last} (ŝ = " in report and "pressure" in report.split("\n")[2]
    if name.startswith("csv") or name in ("calculix", "fe-export"):
        # the distance factor that explains it: 1/1.05 of the distances given
        assert m["diagnosis"]["factor"] == pytest.approx(1 / 1.05, rel=2e-3)


def test_another_solver_passes(no_figures, tmp_path):
    # the FEM (a finite sphere, P2 elements, 125 contact nodes): a different method
    case = wearcheck.load_case("paper", {"fem.contact_nodes": 125})
    fem = wearcheck.solve(case, "fem")
    res = fmt.csv_dir(tmp_path / "fem", fem)
    m = run_verify("paper", res, tmp_path / "v")
    assert m["passed"], json.dumps(failed_stages(m))


def test_stages_between_the_reference_stages(no_figures, tmp_path):
    # the user's stages are not the case's: the reference is interpolated, never the user's
    case = wearcheck.load_case("paper", {"mdr.elements": 400,
                                         "stages.s_hat": [0.07, 0.7, 2.2, 6.6, 9.9]})
    run = wearcheck.solve(case, "mdr")
    m = run_verify("paper", fmt.csv_dir(tmp_path / "r", run), tmp_path / "v")
    assert m["passed"], json.dumps(failed_stages(m))
    got = [st["s_hat_reference"] for st in m["pairs"]["results"]["stages"]]
    assert got == pytest.approx([0.07, 0.7, 2.2, 6.6, 9.9], rel=1e-12)


def test_history_alone_judges_the_history(no_figures, tmp_path, paper_run):
    res = fmt.csv_dir(tmp_path / "r", paper_run, stages=False)
    m = run_verify("paper", res, tmp_path / "v")
    assert m["passed"]
    assert set(m["results"]["not_given"]) == {"f", "p"}
    # stages chosen from the history rows nearest the case's stages
    assert len(m["pairs"]["results"]["stages"]) == 7
    assert "profile_contact_max" not in m["checks"]


def test_missing_quantities_are_listed_not_failed(no_figures, tmp_path, paper_run):
    d = tmp_path / "r"
    d.mkdir()
    h = paper_run.history
    rows = ["s,force"] + [f"{s:.17g},{F:.17g}" for s, F in zip(h["s"], h["force"])]
    (d / "history.csv").write_text("\n".join(rows) + "\n")
    m = run_verify("paper", d, tmp_path / "v")
    assert m["passed"] and m["checks"] == ["force"]
    assert "contact_radius" in m["results"]["not_given"]


def test_against_a_fresh_run(no_figures, tmp_path, paper_run):
    res = fmt.csv_dir(tmp_path / "r", paper_run, scale=1.05)
    m = run_verify("paper", res, tmp_path / "v", reference_solver="mdr")
    assert m["reference"] == "mdr" and not m["passed"]
    res = fmt.csv_dir(tmp_path / "r2", paper_run)
    m = run_verify("paper", res, tmp_path / "v2", reference_solver="mdr")
    assert m["passed"]


def test_other_physics_has_no_certified_reference(no_figures, tmp_path, paper_run):
    res = fmt.csv_dir(tmp_path / "r", paper_run)
    with pytest.raises(CaseError, match="no certified reference.*--reference-solver"):
        run_verify(wearcheck.load_case("paper", {"wear.k": 2e-4}), res, tmp_path / "v")
    # it names the solvers that can run the case (the pin on a disc: the BEM alone)
    with pytest.raises(CaseError) as err:
        run_verify("pin_on_disc", res, tmp_path / "v")
    assert str(err.value).endswith("verify against a fresh run instead: --reference-solver "
                                   "bem (the only solver that runs this case)"), str(err.value)
    assert wearcheck.registry.supporting(wearcheck.load_case("pin_on_disc")) == ("bem",)
    # a resolution or a tolerance is not physics: the reference applies
    m = run_verify(wearcheck.load_case("paper", {"mdr.elements": 100,
                                                 "compare.force_tolerance": 0.05}),
                   res, tmp_path / "v2")
    assert m["passed"]


def test_output_directory(tmp_path, paper_run):
    res = fmt.csv_dir(tmp_path / "r", paper_run)
    out = tmp_path / "v"
    run_verify("paper", res, out)
    for name in ("metrics.json", "report.md", "report.html", "case.toml", "fig_profiles.png",
                 "fig_pressure.png", "history.png", "reference/meta.json",
                 "reference/stages.npz", "results/history.csv", "results/stages.csv"):
        assert (out / name).is_file(), name
    meta = json.loads((out / "reference" / "meta.json").read_text())
    assert meta["solver"] == "reference" and meta["reference"]["provenance"]["command"]
    # the reference's run directory reads back as a run
    back = wearcheck.read_run(out / "reference")
    assert back.solver == "reference"


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "wearcheck", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=300)


def test_cli_exit_codes(tmp_path, paper_run):
    good = fmt.csv_dir(tmp_path / "good", paper_run)
    bad = fmt.csv_dir(tmp_path / "bad", paper_run, scale=1.05)
    done = cli("verify", "paper", good, "--out", tmp_path / "v1", "--quiet")
    assert done.returncode == 0, done.stderr
    done = cli("verify", "paper", bad, "--out", tmp_path / "v2")
    assert done.returncode == 1
    assert "FAIL" in done.stderr and "stage 6" in done.stderr and "force" in done.stderr
    assert "most likely cause" in done.stderr


@pytest.mark.parametrize("history,stages,expect", [
    ("s,force [lbf]\n0,1\n", None, ["history.csv", "row 1", "column 'force [lbf]'",
                                    "unknown unit"]),
    ("s,force\n0,1\n1,abc\n", None, ["history.csv", "row 3", "column 'force'"]),
    ("s,force\n0,1\n0,2\n", None, ["history.csv", "row 3", "column 's'", "increase"]),
    ("force\n1\n", None, ["history.csv", "no column 's', 's_hat' or 'cycles'"]),
    ("s,force\n0,1\n,2\n", None, ["history.csv", "row 3", "column 's'", "empty"]),
    ("s,force\n0,1\n", "s,r,p\n0,0,1\n0,1e-5,oops\n", ["stages.csv", "row 3", "column 'p'"]),
    ("s,force\n0,1\n", "s,r,p\n0,0,1\n0,0,2\n", ["stages.csv", "row 3", "column 'r'",
                                                 "twice"]),
    ("s,force\n0,1\n", "s,r\n0,0\n0,1\n", ["stages.csv", "no column 'f', 'wear' or 'p'"]),
    ("cycles,force\n0,1\n", None, ["cycles", "sliding.stroke"]),
    ("s,force\n0,1\n1,-1\n", None, ["history.csv", "row 3", "column 'force'",
                                     "changes sign"]),
])
def test_bad_files_one_line(tmp_path, history, stages, expect):
    d = tmp_path / "r"
    d.mkdir()
    (d / "history.csv").write_text(history)
    if stages:
        (d / "stages.csv").write_text(stages)
    done = cli("verify", "paper", d, "--out", tmp_path / "v", "--quiet")
    assert done.returncode == 2, done.stderr
    lines = [x for x in done.stderr.splitlines() if x.strip()]
    assert len(lines) == 1, done.stderr
    for part in expect:
        assert part in lines[0], lines[0]


def test_bad_mapping_and_formats(no_figures, tmp_path, paper_run):
    res = fmt.csv_dir(tmp_path / "r", paper_run)
    with pytest.raises(CaseError, match="--map 'pressure=x'.*not a quantity"):
        run_verify("paper", res, tmp_path / "v", ["pressure=x"])
    with pytest.raises(CaseError, match="expected name=field"):
        external.parse_mapping(["p"])
    with pytest.raises(CaseError, match="unknown format"):
        external.read(_touch(tmp_path / "x.txt"))
    pvd = fmt.vtk_series(tmp_path / "vtk", paper_run)
    with pytest.raises(CaseError, match="no point data 'f', 'wear_depth' or 'pressure'"):
        external.read(pvd)
    with pytest.raises(CaseError, match="unknown unit 'psi'"):
        external.read(pvd, external.parse_mapping(["p [psi]=CPRESS"]))


def _touch(path):
    path.write_text("")
    return path


# -- CalculiX's own files -----------------------------------------------------------

CCX_DECK = """*HEADING
two CAX4 blocks pressed together, node-to-surface contact
*NODE,NSET=NALL
1,0.,0.
2,1.,0.
3,2.,0.
4,0.,1.
5,1.,1.
6,2.,1.
7,0.,-1.
8,1.,-1.
9,2.,-1.
10,0.,0.
11,1.,0.
12,2.,0.
*ELEMENT,TYPE=CAX4,ELSET=UPPER
1,1,2,5,4
2,2,3,6,5
*ELEMENT,TYPE=CAX4,ELSET=LOWER
3,7,8,11,10
4,8,9,12,11
*NSET,NSET=TOP
4,5,6
*NSET,NSET=BOTTOM
7,8,9
*NSET,NSET=CONTACT
1,2,3
*SURFACE,NAME=SLAVE,TYPE=NODE
CONTACT
*SURFACE,NAME=MASTER
3,S3
4,S3
*MATERIAL,NAME=EL
*ELASTIC
210000.,0.3
*SOLID SECTION,ELSET=UPPER,MATERIAL=EL
*SOLID SECTION,ELSET=LOWER,MATERIAL=EL
*SURFACE INTERACTION,NAME=SI
*SURFACE BEHAVIOR,PRESSURE-OVERCLOSURE=LINEAR
1.e7
*CONTACT PAIR,INTERACTION=SI,TYPE=NODE TO SURFACE
SLAVE,MASTER
*BOUNDARY
BOTTOM,1,2
1,1,1
4,1,1
7,1,1
10,1,1
*STEP
*STATIC
0.5,1.
*BOUNDARY
TOP,2,2,-0.001
*NODE PRINT,NSET=TOP,TOTALS=ONLY
RF
*NODE PRINT,NSET=CONTACT
U
*EL PRINT,ELSET=UPPER
S
*NODE FILE
U,RF
*CONTACT FILE
CDIS,CSTR
*CONTACT PRINT
CSTR
*END STEP
"""


@pytest.fixture(scope="module")
def ccx_files(tmp_path_factory):
    """A real CalculiX 2.20 job: its .dat and .frd (skipped without ccx)."""
    if shutil.which("ccx") is None:
        pytest.skip("CalculiX (ccx) is not installed")
    d = tmp_path_factory.mktemp("ccx")
    (d / "block.inp").write_text(CCX_DECK)
    done = subprocess.run(["ccx", "-i", "block"], cwd=d, capture_output=True, text=True,
                          timeout=120, env={"OMP_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})
    if done.returncode != 0 or not (d / "block.frd").is_file():
        pytest.skip(f"ccx did not run: {done.stdout[-300:]}")
    return d


def test_real_calculix_files_agree_with_each_other(ccx_files):
    # the reader the ccx solver reads its own jobs with
    from wearcheck import calculix_files as calculix
    nodes, blocks = calculix.read_frd(ccx_files / "block.frd")
    assert len(nodes) == 12 and nodes[2][:2] == (1.0, 0.0)
    dat = calculix.dat_blocks((ccx_files / "block.dat").read_text(), "block.dat")
    for t in (0.5, 1.0):
        # the .frd's CPRESS and the .dat's contact print are two outputs of one solve
        frd = [b for b in blocks if b.name == "CONTACT" and b.time == t][0]
        cstr = [b for b in dat if b.quantity == "contact stress" and b.time == t][0]
        p_frd = dict(zip(frd.ids.tolist(), frd.values[:, frd.components.index("CPRESS")]))
        p_dat = dict(zip(cstr.ids.tolist(), cstr.values[:, 0]))
        assert set(p_frd) == set(p_dat)
        for i in p_dat:   # .frd: 6 digits, .dat: 7
            assert p_frd[i] == pytest.approx(p_dat[i], rel=1e-5)
    # element prints (element, integration point, six stresses) are read and left aside
    stresses = [b for b in dat if b.quantity == "stresses"]
    # CalculiX expands a CAX4 into a C3D8 of eight integration points
    assert len(stresses) == 2 and stresses[0].values.shape == (16, 7)
    assert set(stresses[0].ids.tolist()) == {1, 2}
    ext = external.read(ccx_files / "block.frd", {})
    assert [st.time for st in ext.stages] == [0.5, 1.0]
    assert list(ext.history["force"]) == pytest.approx([1.795942, 3.593273], rel=1e-6)
    # without the .frd, the stages come from the .dat's contact prints and the deck
    (ccx_files / "block.frd").rename(ccx_files / "block.frd.off")
    try:
        ext2 = external.read(ccx_files / "block.dat", {})
    finally:
        (ccx_files / "block.frd.off").rename(ccx_files / "block.frd")
    for a, b in zip(ext.stages, ext2.stages):
        assert np.allclose(a.r, b.r) and np.allclose(a.p, b.p, rtol=1e-5)


def test_damaged_calculix_files(tmp_path, paper_run):
    frd = fmt.calculix(tmp_path / "c", paper_run)
    text = frd.read_text().splitlines()
    text[10] = text[10][:20] + "xx" + text[10][22:]
    frd.write_text("\n".join(text) + "\n")
    with pytest.raises(CaseError, match=r"wear\.frd, line 11"):
        external.read(frd, external.parse_mapping(fmt.CALCULIX_MAP))
    frd = fmt.calculix(tmp_path / "d", paper_run)
    dat = frd.with_suffix(".dat")
    lines = dat.read_text().splitlines()
    lines[3] = lines[3] + " 7"
    dat.write_text("\n".join(lines) + "\n")
    with pytest.raises(CaseError, match=r"wear\.dat, line 4: expected 3 numbers"):
        external.read(frd, external.parse_mapping(fmt.CALCULIX_MAP))


def test_reference_command_and_api(tmp_path):
    out = tmp_path / "ref"
    done = cli("reference", "paper", "--out", out, "--quiet")
    assert done.returncode == 0, done.stderr
    run = wearcheck.read_run(out)
    assert run.solver == "reference"
    assert list(run.stages["s_hat"]) == pytest.approx([0, 0.5, 1.5, 3, 5, 8, 10])
    meta = json.loads((out / "meta.json").read_text())
    assert meta["reference"]["provenance"]["command"].startswith("python benchmarks/")
    ref = wearcheck.reference("paper")
    assert ref.certified.name == "paper" and ref.info["band"]
    # the run directory is itself a results directory (its history.csv): it passes
    m = run_verify("paper", out, tmp_path / "v")
    assert m["passed"]
    done = cli("reference", "--list")
    assert done.returncode == 0 and "fretting" in done.stdout


# -- the other benchmarks: cycles, a single .vtu -------------------------------------

def test_ball_on_flat_in_cycles(no_figures, tmp_path):
    # a lab test's results against the cycle count (s = 2·stroke·cycles)
    run = wearcheck.solve(wearcheck.load_case("ball_on_flat", {"mdr.elements": 200}), "mdr")
    m = run_verify("ball_on_flat", fmt.csv_dir(tmp_path / "r", run, time="cycles"),
                   tmp_path / "v")
    assert m["passed"], json.dumps(failed_stages(m))
    assert m["results"]["distance"] == "cycles"
    m = run_verify("ball_on_flat", fmt.csv_dir(tmp_path / "b", run, time="cycles",
                                               scale=1.05), tmp_path / "v2")
    assert not m["passed"]
    # under a held force the worn volume is K F s: 5 % more distance, 5 % more volume
    assert all("wear_volume" in bad for k, bad in failed_stages(m).items() if k > 0)
    assert m["diagnosis"]["factor"] == pytest.approx(1 / 1.05, rel=2e-3)


def test_a_case_staged_in_cycles_against_a_fresh_run(no_figures, tmp_path):
    """--reference-solver failed on every case whose stages are in cycles ("key
    'stages.cycles' = None: must be a non-empty list of numbers"). The fresh run's
    stages are now the user's (as ŝ): the same solver at the same resolution passes,
    its results at 1.05 times the distance fail, at the case's seven stages."""
    case = wearcheck.load_case("ball_on_flat", {"mdr.elements": 200})
    run = wearcheck.solve(case, "mdr")
    m = run_verify(case, fmt.csv_dir(tmp_path / "r", run, time="cycles"), tmp_path / "v",
                   reference_solver="mdr")
    assert m["reference"] == "mdr" and m["passed"], json.dumps(failed_stages(m))
    got = [st["s_hat_reference"] for st in m["pairs"]["results"]["stages"]]
    assert got == pytest.approx(run.stages["s_hat"], rel=1e-9)
    m = run_verify(case, fmt.csv_dir(tmp_path / "b", run, time="cycles", scale=1.05),
                   tmp_path / "v2", reference_solver="mdr")
    assert not m["passed"]


def test_fretting_in_cycles(no_figures, tmp_path):
    # the fretting benchmark over half its cycles (the run's length is free; 2 s of MDR).
    # Not fewer: the worn volume is judged against the larger of its own value and 1 %
    # of π a0² d0 (compare.profile_floor), which it passes at about 2e4 cycles; at 1000
    # cycles 5 % more sliding shifts it by 0.2 % of that floor and the verdict cannot see
    # it (measured: 0.00215 of 0.01 allowed; at 1e4 and 5e4 cycles 0.022 and 0.056)
    case = wearcheck.load_case("fretting", {"mdr.elements": 200, "fretting.cycles": 50000,
                                            "fretting.stage_cycles": [0, 100, 10000, 50000]})
    run = wearcheck.solve(case, "mdr")
    m = run_verify(case, fmt.csv_dir(tmp_path / "r", run, time="cycles"), tmp_path / "v")
    assert m["passed"], json.dumps(failed_stages(m))
    m = run_verify(case, fmt.csv_dir(tmp_path / "b", run, time="cycles", scale=1.05),
                   tmp_path / "v2")
    failed = failed_stages(m)
    assert not m["passed"] and "wear_volume" in failed[max(failed)]
    # against a fresh run at the results' cycle counts
    m = run_verify(case, fmt.csv_dir(tmp_path / "r2", run, time="cycles", stages=False),
                   tmp_path / "v3", reference_solver="mdr")
    assert m["passed"] and m["reference"] == "mdr"


def test_a_single_vtu_of_the_unworn_contact(no_figures, tmp_path):
    out = tmp_path / "run"
    run = wearcheck.solve(wearcheck.load_case("hertz", {"fem.contact_nodes": 125}), "fem")
    run.write(out)
    wearcheck.export_vtk(out)
    m = run_verify("hertz", out / "vtk" / "profile_000.vtu", tmp_path / "v")
    assert m["passed"], json.dumps(failed_stages(m))
    assert m["checks"] == ["profile_contact_max", "pressure_interior_max"]


def test_the_ellipsoid_as_an_equivalent_sphere_fails(no_figures, tmp_path):
    # the MDR's axisymmetric stand-in (the paraboloid of radius √(R1 R2)) is not the
    # ellipsoid: it misses the BEM reference's profile and ring-averaged pressure by
    # far more than the tolerance and the reference's own (wide) band together
    run = wearcheck.solve("ellipsoid", "mdr")
    m = run_verify("ellipsoid", fmt.csv_dir(tmp_path / "r", run), tmp_path / "v")
    assert not m["passed"]
    failed = failed_stages(m)
    assert "profile_contact_max" in failed[0] and "pressure_interior_max" in failed[6]
    for st in m["pairs"]["results"]["stages"]:
        for name, c in st["checks"].items():
            # judged: a certified reference there, or a miss beyond tolerance and band
            assert st["band"][name] <= c["tolerance"] / 3 or \
                c["value"] > c["tolerance"] + st["band"][name]


def test_an_uncertain_reference_decides_nothing(no_figures, tmp_path, paper_run, monkeypatch):
    # a reference whose force band were half the force tolerance: the right results'
    # force is not judged (listed with both numbers), the 5 %-off results' still fails
    # where it misses by more than tolerance and band
    from wearcheck.references import certified
    band_at = certified.Reference.band_at

    def wide(self, s):
        out = band_at(self, s)
        out["force"] = 0.5 * 0.03 * float(self.history_at(s)["force"][0])
        return out
    monkeypatch.setattr(certified.Reference, "band_at", wide)
    m = run_verify("paper", fmt.csv_dir(tmp_path / "r", paper_run), tmp_path / "v")
    assert m["passed"] and "force" not in m["checks"]
    notes = m["pairs"]["results"]["not_judged"]
    assert len(notes) == 7 and all("force (the reference's own error 0.015" in n
                                   for n in notes)
    m = run_verify("paper", fmt.csv_dir(tmp_path / "b", paper_run, scale=1.05),
                   tmp_path / "v2")
    last = m["pairs"]["results"]["stages"][-1]
    assert not last["checks"]["force"]["passed"]       # 0.23 > 0.03 + 0.015


def test_results_that_stop_early_fail(no_figures, tmp_path, paper_run):
    """Results must reach the case's last stage: a one-row history (the unworn force
    alone) and an honest history cut after ŝ = 0.5 would otherwise pass on the stages
    they hold (1 of 7, 3 of 7), as compare fails a solver that stopped early."""
    one = tmp_path / "one"
    one.mkdir()
    (one / "history.csv").write_text("s,force\n0,30.7\n", encoding="utf-8")
    m = run_verify("paper", one, tmp_path / "v1")
    reach = m["pairs"]["results"]["reach"]
    assert not m["passed"] and not reach["passed"] and reach["end_s"] == 0.0
    per_m = m["scales"]["s_hat_per_m"]
    case_s_hat = wearcheck.load_case("paper").stages.s_hat
    assert [s * per_m for s in reach["not_reached"]] == pytest.approx(case_s_hat[1:], rel=1e-12)
    # the stage it holds is right (F0 = 30.7 N to 0.3 %): only the reach fails it
    assert all(st["passed"] for st in m["pairs"]["results"]["stages"])

    res = fmt.csv_dir(tmp_path / "cut", paper_run, stages=False)
    lines = (res / "history.csv").read_text().splitlines()
    col = lines[0].split(",").index("s [mm]")
    keep = [ln for ln in lines[1:] if float(ln.split(",")[col]) / 1e3 * per_m <= 0.6]
    (res / "history.csv").write_text("\n".join(lines[:1] + keep) + "\n", encoding="utf-8")
    done = cli("verify", "paper", res, "--out", tmp_path / "v2")
    assert done.returncode == 1, done.stderr
    assert "verify: FAIL" in done.stderr
    assert "the case's stage(s) at ŝ = 1.5, 3, 5, 8, 10 not reached" in done.stderr
    end = max(float(ln.split(",")[col]) / 1e3 * per_m for ln in keep)
    assert f"your results end at ŝ = {end:.4g}" in done.stderr
    # the full history passes (test_history_alone_judges_the_history): the cut alone fails it


@pytest.mark.parametrize("factor", [1e3, 1e6])
def test_distances_in_the_wrong_unit_fail(no_figures, tmp_path, paper_run, factor):
    """A history whose distances are written in mm or µm under a header that says
    metres reaches far past the case's last stage, so the reach check passes; its
    rows nearest the case's stages are then the unworn row (ŝ = 0) and rows far
    beyond the reference. Judging the unworn row alone passed such results (exit 0,
    1 of 7 stages judged). The case's last stage must have a row near it (nearer to
    it than to the stage before, the midpoint of the two): else the verdict fails
    and says where the rows are. A sparse honest history (rows at ŝ = 0, 2, 9.9, 11)
    still passes: its row 9.9 is the last stage's."""
    h = paper_run.history
    per_m = paper_run.scales["s_hat_per_m"]
    wrong = tmp_path / "wrong"
    wrong.mkdir()
    rows = [f"{s * factor:.17g},{F:.17g}" for s, F in zip(h["s"], h["force"])]
    (wrong / "history.csv").write_text("s,force\n" + "\n".join(rows) + "\n", encoding="utf-8")
    m = run_verify("paper", wrong, tmp_path / "v-wrong")
    assert not m["passed"]
    done = cli("verify", "paper", wrong, "--out", tmp_path / "v-wrong-cli")
    assert done.returncode == 1, done.stderr
    assert "no row of your results near the case's last stage at ŝ = 10" in done.stderr
    assert "check the unit of the sliding distance" in done.stderr

    # sparse but honest: the reference's own values at ŝ = 0, 2, 9.9 and 11
    sparse = tmp_path / "sparse"
    sparse.mkdir()
    s_hat = np.array([0.0, 2.0, 9.9, 11.0])
    force = np.interp(s_hat, np.asarray(h["s"]) * per_m, h["force"])
    rows = [f"{x / per_m:.17g},{F:.17g}" for x, F in zip(s_hat, force)]
    (sparse / "history.csv").write_text("s,force\n" + "\n".join(rows) + "\n", encoding="utf-8")
    m = run_verify("paper", sparse, tmp_path / "v-sparse")
    assert m["passed"], json.dumps(failed_stages(m))


def test_vtk_points_without_values_inside_the_surface_are_refused(no_figures, tmp_path,
                                                                  paper_run):
    """A .vtu whose pressure is NaN over most of the contact (a failed export, a
    result field defined on part of the surface) was judged on the points left
    (PASS, exit 0, as a CSV with an empty cell is refused). Points without a value
    between points with values in radius are a hole in the data: refused in one
    line naming the file, the count and the radii. NaN beyond the last point with
    values (a field on the contact's selection only) is left out with a note."""
    import meshio
    pvd = fmt.vtk_series(tmp_path / "res", paper_run)
    for vtu in sorted(pvd.parent.glob("surf_*.vtu")):
        m = meshio.read(vtu)
        r = np.hypot(m.points[:, 0], m.points[:, 1])        # mm
        p = m.point_data["CPRESS"]
        p[(r > 0.01) & (r < 0.12)] = np.nan                   # inside a0 = 0.1 mm
        meshio.write(vtu, m)
    with pytest.raises(CaseError, match=r"surf_000\.vtu.*point\(s\) without a finite value "
                                        r"at radii .* between points with values"):
        run_verify("paper", pvd, tmp_path / "v-holes", fmt.VTK_MAP)
    done = cli("verify", "paper", pvd, "--out", tmp_path / "v-holes-cli", *[
        a for kv in fmt.VTK_MAP for a in ("--map", kv)])
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr

    tail = fmt.vtk_series(tmp_path / "tail", paper_run)
    for vtu in sorted(tail.parent.glob("surf_*.vtu")):
        m = meshio.read(vtu)
        r = np.hypot(m.points[:, 0], m.points[:, 1])
        m.point_data["CPRESS"][r > 0.17] = np.nan              # beyond every stage's contact
        meshio.write(vtu, m)
    m = run_verify("paper", tail, tmp_path / "v-tail", fmt.VTK_MAP)
    assert m["passed"], json.dumps(failed_stages(m))
    assert any("without a finite value" in n for n in m["results"]["notes"])


def test_a_history_wrong_between_the_stages_fails(no_figures, tmp_path, paper_run):
    """Only the rows at the case's stages were judged: a history right at the seven
    stage rows and 1.5× off everywhere between them passed (exit 0). Every row the
    reference covers is now judged as a stage's history is; the same history with
    every row right passes (the right results are the MDR's at N = 400, which pass
    at the stages with the shipped tolerances)."""
    h = paper_run.history
    per_m = paper_run.scales["s_hat_per_m"]
    s_hat = np.asarray(h["s"]) * per_m
    stage_hat = np.asarray(wearcheck.load_case("paper").stages.s_hat, float)
    near = np.zeros(len(s_hat), bool)
    for x in stage_hat:
        near[int(np.argmin(np.abs(s_hat - x)))] = True
    for name, factor in (("right", 1.0), ("wrong", 1.5)):
        d = tmp_path / name
        d.mkdir()
        force = np.where(near, h["force"], factor * np.asarray(h["force"]))
        rows = [f"{s:.17g},{F:.17g}" for s, F in zip(h["s"], force)]
        (d / "history.csv").write_text("s,force\n" + "\n".join(rows) + "\n", encoding="utf-8")
        m = run_verify("paper", d, tmp_path / f"v-{name}")
        rows_verdict = m["pairs"]["results"]["rows"]
        assert rows_verdict["judged"] > 50
        if factor == 1.0:
            assert m["passed"], json.dumps(rows_verdict["worst"])
        else:
            assert not m["passed"] and not rows_verdict["passed"]
            assert rows_verdict["failed"] >= rows_verdict["judged"] // 2
            assert failed_stages(m) == {}          # the stages alone still pass
    done = cli("verify", "paper", tmp_path / "wrong", "--out", tmp_path / "v-wrong-cli")
    assert done.returncode == 1, done.stderr
    assert "history row(s) between the stages beyond a tolerance" in done.stderr


def test_a_mapping_judges_the_mapped_column(no_figures, tmp_path, paper_run):
    """A file with 'force [N]' (a friction force, 0.3 of the normal force) and 'Fn [N]'
    (the normal force, right): --map force=Fnn (a typo) judged the friction column
    and failed it; --map force=Fn failed with "column 'force' appears twice". Now
    the typo is one line naming the columns there are (exit 2), and the mapped column
    is judged (it passes; the friction column would fail by 70 %), the report saying
    which column was read and which was not."""
    h = paper_run.history
    d = tmp_path / "r"
    d.mkdir()
    rows = [f"{s:.17g},{0.3 * F:.17g},{F:.17g}" for s, F in zip(h["s"], h["force"])]
    (d / "history.csv").write_text("s [m],force [N],Fn [N]\n" + "\n".join(rows) + "\n")
    done = cli("verify", "paper", d, "--out", tmp_path / "v1", "--map", "force=Fnn")
    lines = [x for x in done.stderr.splitlines() if x.strip() and not x.startswith("note")]
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert "no column 'Fnn' in file" in lines[0] and "'Fn [N]'" in lines[0], lines[0]
    m = run_verify("paper", d, tmp_path / "v2", ["force=Fn"])
    assert m["passed"], json.dumps(failed_stages(m))
    assert ("history.csv: force read from column 'Fn [N]' (--map force=Fn); column "
            "'force [N]' not read") in m["results"]["notes"]
    # a stage column mapped without a stages.csv is not silently unused
    with pytest.raises(CaseError, match=r"--map p=CPRESS: .*stages\.csv does not exist"):
        run_verify("paper", d, tmp_path / "v3", ["force=Fn", "p=CPRESS"])


def test_a_row_between_the_stages_is_named_by_its_line(no_figures, tmp_path, paper_run):
    """The worst row between the stages was named by its index from 0 ("row 167" was
    the file's line 169). One row made 1.5× off in a file with a comment line above
    the header: its line number is known by construction (comment 1, header 2, data
    row k on line k + 3) and is the one named."""
    h = paper_run.history
    per_m = paper_run.scales["s_hat_per_m"]
    s_hat = np.asarray(h["s"]) * per_m
    k = int(np.argmin(np.abs(s_hat - 4.0)))       # between the stages at ŝ = 3 and 5
    force = np.asarray(h["force"], float).copy()
    force[k] *= 1.5
    d = tmp_path / "r"
    d.mkdir()
    rows = [f"{s:.17g},{F:.17g}" for s, F in zip(h["s"], force)]
    (d / "history.csv").write_text("# one row wrong\ns,force\n" + "\n".join(rows) + "\n")
    m = run_verify("paper", d, tmp_path / "v")
    worst = m["pairs"]["results"]["rows"]["worst"]["force"]
    assert not m["passed"] and worst["index"] == k
    assert worst["origin"] == f"history.csv row {k + 3}"
    report = (tmp_path / "v" / "report.md").read_text()
    assert f"at ŝ = {s_hat[k]:.4g} (history.csv row {k + 3})" in report


def _history_and_stages(d, run, *, s_factor=1.0, p_factor=1.0, f_as_wear=False):
    """The run's history (s, force, central wear) and stages (s_hat, r, f, p) in SI
    headers, with the slips asked for: distances times s_factor (1e3: mm under 's'),
    the pressure times p_factor (1e-6: MPa under 'p'), the wear depth under 'f'."""
    from wearcheck.references.certified import unworn_profile
    d.mkdir()
    h, st = run.history, run.stages
    rows = [f"{s * s_factor:.17g},{F:.17g},{w:.17g}"
            for s, F, w in zip(h["s"], h["force"], h["wear_center"])]
    (d / "history.csv").write_text("s,force,wear_center\n" + "\n".join(rows) + "\n")
    f0 = unworn_profile(run.case, st["r"]) if f_as_wear else np.zeros(len(st["r"]))
    rows = [f"{x:.17g},{r:.17g},{st['f'][k, j] - f0[j]:.17g},{st['p'][k, j] * p_factor:.17g}"
            for k, x in enumerate(st["s_hat"]) for j, r in enumerate(st["r"])]
    (d / "stages.csv").write_text("s_hat,r,f,p\n" + "\n".join(rows) + "\n")
    return d


def test_the_diagnosis_says_agree_only_where_it_agrees(no_figures, tmp_path, paper_run):
    """With s in mm under an 's' header the diagnosis said "your results agree with
    the reference at 0.5 × your sliding distances (misfit 2.6 there, 15 as given)":
    0.5 is the end of the range searched and a misfit of 2.6 (260 %) is no agreement.
    "Agree" now needs λ strictly inside the range and the misfit within the
    verdict's tolerance (the largest of the quantities' tolerances, here 3 %);
    distances in mm under a header in metres are named as such (the reference fits
    at 1e-3 of them: exactly, by construction); otherwise the units are pointed at."""
    from wearcheck.studies.verify import _diagnosis
    cmp = wearcheck.load_case("paper").compare
    for lam in (0.5, 0.8):                          # the reviewer's numbers
        factor = dict(factor=lam, misfit=2.6, misfit_at_one=15.0, quantities=["force"],
                      bounds=[0.5, 2.0], unit_misfits=[])
        said = _diagnosis({"passed": False}, factor, cmp, "s", [])["reason"]
        assert "agree with the reference at" not in said, said
        assert "check the units of your columns" in said, said
        assert ("the end of that range" in said) == (lam == 0.5), said
    m = run_verify("paper", _history_and_stages(tmp_path / "mm", paper_run, s_factor=1e3),
                   tmp_path / "v")
    assert not m["passed"]
    assert "mm written under a header in metres (write 's [mm]')" in m["diagnosis"]["reason"]
    assert m["diagnosis"]["factor"] == 1e-3
    # 1e3 × the distances leaves the reference: no misfit there, and valid JSON
    assert "Infinity" not in (tmp_path / "v" / "metrics.json").read_text()


@pytest.mark.parametrize("slip,said", [
    (dict(p_factor=1e-6), "your pressure is 1e-06 times the reference's: MPa written under "
                          "a header in Pa"),
    (dict(f_as_wear=True), "your profile 'f' matches the reference's wear depth f − f0"),
])
def test_unit_slips_in_the_stages_are_hinted(no_figures, tmp_path, paper_run, slip, said):
    """MPa written under 'p' (Pa) failed "pressure 1 > 0.03" at every stage, and a wear
    depth written as the profile 'f' failed at ~100 %, without a word on why. The
    hint names the slip; the verdict stays FAIL. The same tables without the slip
    pass (the MDR at N = 400 passes with the shipped tolerances)."""
    m = run_verify("paper", _history_and_stages(tmp_path / "ok", paper_run), tmp_path / "v0")
    assert m["passed"], json.dumps(failed_stages(m))
    m = run_verify("paper", _history_and_stages(tmp_path / "r", paper_run, **slip),
                   tmp_path / "v")
    assert not m["passed"]
    assert said in m["diagnosis"]["reason"], m["diagnosis"]
