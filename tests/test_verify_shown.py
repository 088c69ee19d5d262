"""What ``wearcheck verify`` shows a user: the history figure makes a failure visible,
the terminal says what each ``--map`` read, and a ``--map`` naming an array, field,
block or set that a VTK or CalculiX input lacks is refused in one line naming what
the file has.

The results are the certified reference of the paper case itself (what
``wearcheck reference paper --out ref/`` writes), so each difference is known by
construction: zero as given, and exactly 8 % of the reference's force (relative to
the force, floored at force_floor) with the force written 1.08 times too large.
"""

import subprocess
import sys

import numpy as np
import pytest

import wearcheck
from wearcheck import external
from wearcheck.cases import CaseError
from wearcheck.comparisons.present import verify_figures

import verify_formats as fmt


@pytest.fixture(scope="module")
def reference():
    """The paper case's certified reference as a result (history, stages, case)."""
    return wearcheck.reference("paper")


def write_history(d, ref, *, force_factor=1.0, friction=False):
    """history.csv of the reference's history in SI, the force times ``force_factor``;
    with ``friction`` the normal force under 'Fn [N]' and a friction force (0.3 F)
    under 'force [N]', as a user's export with both may hold them."""
    h = ref.history
    d.mkdir(parents=True)
    cols = ["contact_radius", "wear_center", "wear_volume", "depth"]
    head = "s," + ("force [N],Fn [N]," if friction else "force,") + ",".join(cols)
    rows = []
    for i in range(len(h["s"])):
        F = h["force"][i] * force_factor
        forces = [0.3 * h["force"][i], F] if friction else [F]
        rows.append(",".join(f"{v:.17g}" for v in [h["s"][i], *forces]
                             + [h[c][i] for c in cols]))
    (d / "history.csv").write_text(head + "\n" + "\n".join(rows) + "\n")
    return d


@pytest.fixture
def drawn(monkeypatch):
    """The history figures a verify draws (not saved: the artists are what is checked)."""
    figs = []

    def keep(stem, ref_hist, hist, sc, depth, stage_s_hat, formats=(), judged=None,
             failed=None):
        figs.append((verify_figures.history_axes(ref_hist, hist, sc, depth, stage_s_hat,
                                                 judged=judged, failed=failed), hist, sc))
        return []
    monkeypatch.setattr(verify_figures, "history_figure", keep)
    yield figs
    import matplotlib.pyplot as plt
    for fig, _, _ in figs:
        plt.close(fig)


def _panel(fig, ylabel):
    return [ax for ax in fig.axes if ax.get_ylabel() == ylabel][0]


def _failed_x(ax):
    return np.concatenate([np.asarray(line.get_xdata(), float) for line in ax.lines
                           if line.get_gid() == "failed"] or [np.array([])])


def test_history_figure_shows_a_force_8_percent_off_beyond_its_band(tmp_path, reference,
                                                                    drawn):
    """An 8 % force error is a near-coincident curve on F/F0 (the finding): the
    difference panel must draw the ±force_tolerance band, the rows at their 8 %
    (relative to the force, floored at force_floor: the closed form below), and mark
    every failing row; the quantities written right (differences ~1e-13) lie at 0
    inside their bands, unmarked."""
    case = wearcheck.load_case("paper")
    tol, floor = case.compare.force_tolerance, case.compare.force_floor
    bad = write_history(tmp_path / "bad", reference, force_factor=1.08)
    m = wearcheck.verify("paper", bad, tmp_path / "v-bad")
    assert not m["passed"]
    fig, hist, sc = drawn[-1]
    per_m = sc["s_hat_per_m"]
    low = _panel(fig, "ΔF / F [%]")
    # the tolerance as a band from -tol to +tol (in %)
    band = [p for p in low.patches if p.get_gid() == "tolerance"]
    assert len(band) == 1
    y = band[0].get_path().transformed(band[0].get_patch_transform()).vertices[:, 1]
    assert (y.min(), y.max()) == pytest.approx((-100 * tol, 100 * tol))
    lines = {round(float(line.get_ydata()[0]), 9) for line in low.lines
             if line.get_gid() == "tolerance_line"}
    assert lines == {round(-100 * tol, 9), round(100 * tol, 9)}
    # the rows' differences: 0.08 F / max(F, floor·F0), F the reference's force
    rows = [line for line in low.lines if line.get_label() == "results"][0]
    F = np.asarray(reference.history["force"], float) / sc["F0"]
    expect = 100 * 0.08 * F / np.maximum(F, floor)
    s_hat = np.asarray(reference.history["s"], float) * per_m
    assert np.asarray(rows.get_xdata()) == pytest.approx(s_hat, rel=1e-12)
    # 1e-9: the reference read back from its own history (round-off of 17 digits)
    assert np.asarray(rows.get_ydata()) == pytest.approx(expect, rel=1e-9)
    assert np.all(expect > 100 * tol)       # every row fails: every row is marked
    assert np.sort(_failed_x(low)) == pytest.approx(np.sort(s_hat), rel=1e-12)
    top = _panel(fig, "F / F0")
    assert _failed_x(top).size == len(s_hat)
    for label, q in (("Δa / a [%]", "contact_radius"), ("Δw(0) / w(0) [%]", "wear_center"),
                     ("ΔV / V [%]", "wear_volume"), ("Δd / d [%]", "depth")):
        ax = _panel(fig, label)
        assert _failed_x(ax).size == 0, q
        ys = np.asarray([line for line in ax.lines if line.get_label() == "results"][0]
                        .get_ydata())
        assert np.nanmax(np.abs(ys)) < 1e-6, q
    # the figure's verdict agrees with the metrics: the stages failed in force only
    assert {c for st in m["pairs"]["results"]["stages"] for c, v in st["checks"].items()
            if not v["passed"]} == {"force"}


def test_history_figure_of_a_pass_marks_nothing_and_labels_do_not_overlap(
        tmp_path, reference, drawn):
    """The same history written right: no row marked; and no panel's labels reach
    into the next panel (the finding: y-labels overlapped the neighbour), measured on
    the drawn figure's bounding boxes."""
    good = write_history(tmp_path / "good", reference)
    m = wearcheck.verify("paper", good, tmp_path / "v-good")
    assert m["passed"]
    fig = drawn[-1][0]
    assert all(_failed_x(ax).size == 0 for ax in fig.axes)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    rows = {}
    for ax in fig.axes:
        rows.setdefault(round(ax.get_position().y0, 3), []).append(ax)
    assert len(rows) == 2
    for axes in rows.values():
        axes.sort(key=lambda ax: ax.get_position().x0)
        for left, right in zip(axes, axes[1:]):
            # the whole of the left panel (its tick labels included) ends before the
            # right panel's y-label and tick labels begin
            assert left.get_tightbbox(renderer).x1 <= right.get_tightbbox(renderer).x0 + 0.5


def cli(*args):
    return subprocess.run([sys.executable, "-m", "wearcheck", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("factor,passed", [(1.0, True), (1.08, False)])
def test_the_terminal_says_which_column_a_mapping_read(tmp_path, reference, factor, passed):
    """The report said it; the terminal did not: a user with a friction force under
    'force [N]' saw a verdict without knowing which column was judged. One line per
    --map item, after the verdict's lines, on a PASS and on a FAIL."""
    d = write_history(tmp_path / "r", reference, force_factor=factor, friction=True)
    done = cli("verify", "paper", d, "--out", tmp_path / "v", "--map", "force=Fn",
               "--map", "s [m]=s")
    assert done.returncode == (0 if passed else 1), done.stderr
    lines = done.stderr.splitlines()
    said = ("history.csv: force read from column 'Fn [N]' (--map force=Fn); column "
            "'force [N]' not read")
    verdict = [i for i, x in enumerate(lines) if x.startswith("verify: ")]
    at = [i for i, x in enumerate(lines) if x.strip() == said]
    assert len(verdict) == 1 and len(at) == 1, done.stderr
    assert at[0] > verdict[0]
    assert lines[verdict[0]].startswith("verify: PASS" if passed else "verify: FAIL")
    if not passed:      # after the failures and the cause, not among them
        assert "most likely cause" in "\n".join(lines[verdict[0]:at[0]])
    assert sum("(--map " in x for x in lines) == 2
    assert any(x.strip() == "history.csv: s read from column 's' in m (--map 's [m]=s')"
               for x in lines), done.stderr


def test_vtk_and_calculix_say_what_each_mapping_read(tmp_path, reference):
    pvd = fmt.vtk_series(tmp_path / "vtk", reference)
    ext = external.read(pvd, external.parse_mapping(fmt.VTK_MAP))
    assert ext.mapped == [
        "surf.pvd: p read from point data 'CPRESS' in MPa (--map 'p [MPa]=CPRESS')",
        "surf.pvd: f read from point data 'PROFILE' in mm (--map 'f [mm]=PROFILE')",
        "surf.pvd: the radius is the distance from the z axis (--map axis=z)",
        "surf.pvd: r is the points' distance from the axis, their coordinates read in mm "
        "(--map 'r [mm]=points')",
        "surf.pvd: s read from the .pvd timesteps in mm (--map 's [mm]=time')"]
    frd = fmt.calculix(tmp_path / "ccx", reference)
    ext = external.read(frd, external.parse_mapping(fmt.CALCULIX_MAP))
    assert "wear.dat: force read from the total force of set TOP × 180 (--map force=TOP*180)" \
        in ext.mapped
    assert ("wear.frd: wear read from block WEAR component W in mm (--map 'wear [mm]=WEAR.W')"
            in ext.mapped)
    assert len(ext.mapped) == len(fmt.CALCULIX_MAP)


# -- a --map naming what the file lacks ---------------------------------------------

def _map(items, **change):
    """fmt's mapping with items replaced by name: _map(fmt.VTK_MAP, p='p=CPRES')."""
    out = [x for x in items if x.split("=")[0].split(" [")[0] not in change]
    return external.parse_mapping(out + list(change.values()))


def test_vtk_mapping_to_a_missing_array_or_field_is_refused(tmp_path, reference):
    """--map p=CPRES (a typo) with the profile found: the stages were judged without
    their pressure, silently. Now one line naming the array and those the file has;
    the same for field data (the history) and the distance's field."""
    pvd = fmt.vtk_series(tmp_path / "vtk", reference)
    with pytest.raises(CaseError) as err:
        external.read(pvd, _map(fmt.VTK_MAP, p="p [MPa]=CPRES"))
    msg = str(err.value)
    assert "surf_000.vtu" in msg and "no point data 'CPRES'" in msg
    assert "its point data: CPRESS, PROFILE" in msg and "\n" not in msg
    with pytest.raises(CaseError, match=r"no field data 'Fz' \(--map force=Fz\); its field "
                                        r"data: none"):
        external.read(pvd, _map(fmt.VTK_MAP, force="force=Fz"))
    with pytest.raises(CaseError, match=r"no field data 'step' for the distance .*its field "
                                        r"data: none"):
        external.read(pvd, _map(fmt.VTK_MAP, s="s=step"))
    # a history.csv beside the series: a mapped history quantity is its column
    write_history(tmp_path / "vtk" / "h", reference, friction=True)
    (tmp_path / "vtk" / "h" / "history.csv").rename(tmp_path / "vtk" / "history.csv")
    ext = external.read(pvd, _map(fmt.VTK_MAP, force="force=Fn"))
    assert ext.history["force"] == pytest.approx(np.asarray(reference.history["force"]),
                                                 rel=1e-15)
    assert ("history.csv: force read from column 'Fn [N]' (--map force=Fn); column "
            "'force [N]' not read") in ext.mapped
    with pytest.raises(CaseError, match="no column 'Fnn'"):
        external.read(pvd, _map(fmt.VTK_MAP, force="force=Fnn"))


def test_calculix_mapping_to_a_missing_block_or_set_is_refused(tmp_path, reference):
    frd = fmt.calculix(tmp_path / "ccx", reference)
    for change, said in (
            (dict(wear="wear [mm]=WEARX.W"),
             r"wear\.frd: no block 'WEARX' \(--map 'wear \[mm\]=WEARX\.W'\); its blocks: "
             r"CONTACT, WEAR$"),
            (dict(wear="wear [mm]=WEAR.X"),
             r"wear\.frd: block WEAR has no component 'X' .*its components: W;"),
            (dict(p="p [MPa]=CONTACT"),
             r"block CONTACT has no component named .*its components: COPEN, CSLIP1"),
            (dict(depth="depth [mm]=TIPX"),
             r"wear\.dat: no displacements printed for set TIPX .*sets with displacements "
             r"printed: TIP$"),
            (dict(force="force=TOPX*180"), r"no total force of set TOPX \(sets with totals: "
                                           r"TOP\)")):
        with pytest.raises(CaseError, match=said):
            external.read(frd, _map(fmt.CALCULIX_MAP, **change))
    # the force and the depth named without the .dat that prints them
    frd.with_suffix(".dat").unlink()
    with pytest.raises(CaseError, match=r"--map force=TOP\*180: no \.dat file beside .*wear\.frd"):
        external.read(frd, external.parse_mapping(
            [x for x in fmt.CALCULIX_MAP if not x.startswith("depth")]))


@pytest.mark.parametrize("fmt_name", ["vtk", "calculix"])
def test_the_cli_refuses_a_missing_field_in_one_line(tmp_path, reference, fmt_name):
    if fmt_name == "vtk":
        path = fmt.vtk_series(tmp_path / "r", reference)
        items = [x for x in fmt.VTK_MAP if not x.startswith("p ")] + ["p [MPa]=CPRES"]
        expect = ["surf_000.vtu", "'CPRES'", "CPRESS, PROFILE"]
    else:
        path = fmt.calculix(tmp_path / "r", reference)
        items = [x for x in fmt.CALCULIX_MAP if not x.startswith("wear")] + ["wear=WEARX.W"]
        expect = ["wear.frd", "'WEARX'", "CONTACT, WEAR"]
    args = [a for x in items for a in ("--map", x)]
    done = cli("verify", "paper", path, "--out", tmp_path / "v", "--quiet", *args)
    lines = [x for x in done.stderr.splitlines() if x.strip() and not x.startswith("note")]
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    for part in expect:
        assert part in lines[0], lines[0]
