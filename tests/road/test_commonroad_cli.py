"""`mufusion import-commonroad`: bad input exits 2 naming the problem; a good import writes TOML.

The option checks run without the ``commonroad`` extra; the ones that read a file skip without it.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
from typer.testing import CliRunner

from mufusion.cli import app

DATA = Path(__file__).resolve().parents[1] / "data" / "commonroad"
GUETERSLOH = str(DATA / "DEU_Guetersloh-36_1_T-1.xml")
STARNBERG = str(DATA / "DEU_Starnberg-1_1_T-1.xml")
HAS_EXTRA = all(importlib.util.find_spec(name) is not None
                for name in ("commonroad", "commonroad_clcs", "commonroad_route_planner"))
needs_extra = pytest.mark.skipif(not HAS_EXTRA, reason="the commonroad extra is not installed")


def _run(*args: str):
    return CliRunner().invoke(app, ["import-commonroad", *args])


def _said(result) -> str:
    return " ".join(result.output.split())


def _assert_refused(args: list[str], fragment: str, tmp_path: Path) -> None:
    """Exit 2, the problem named, nothing written."""
    out = tmp_path / "road.toml"
    result = _run(*args, "--out", str(out))
    assert result.exit_code == 2, result.output
    assert fragment in _said(result)
    assert not out.exists()


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        ([GUETERSLOH], "give either --planning-problem ID or --lanelet ID --length-m L"),
        ([GUETERSLOH, "--planning-problem", "1", "--lanelet", "84591", "--length-m", "200"],
         "give either"),
        ([GUETERSLOH, "--lanelet", "84591"], "--lanelet needs --length-m"),
        ([GUETERSLOH, "--lanelet", "84591,x", "--length-m", "200"], "--lanelet must be a lanelet"),
        ([GUETERSLOH, "--lanelet", "84591", "--length-m", "30"],
         "--length-m 30 is shorter than a run needs"),
        ([GUETERSLOH, "--planning-problem", "1", "--vehicle", "bus"], "--vehicle must be one of"),
        ([GUETERSLOH, "--planning-problem", "1", "--speed-mps", "0"],
         "--speed-mps 0: Input should be greater than 0"),
        ([GUETERSLOH, "--planning-problem", "1", "--mu", "2"],
         "--mu 2: Input should be less than or equal to 1.5"),
        ([GUETERSLOH, "--planning-problem", "1", "--smoothing", "spline"], "--smoothing must be"),
    ],
)
def test_bad_options_exit_2_before_reading(args, fragment: str, tmp_path: Path) -> None:
    _assert_refused(args, fragment, tmp_path)


def test_missing_and_foreign_files_exit_2(tmp_path: Path) -> None:
    out = tmp_path / "road.toml"
    missing = _run(str(tmp_path / "nowhere.xml"), "--planning-problem", "1", "--out", str(out))
    assert missing.exit_code == 2 and "does not exist" in _said(missing)
    foreign = tmp_path / "notes.xml"
    foreign.write_text("<osm version='0.6'></osm>")
    if HAS_EXTRA:
        result = _run(str(foreign), "--planning-problem", "1", "--out", str(out))
        assert result.exit_code == 2 and "is not a CommonRoad XML file" in _said(result)
    assert not out.exists()


@needs_extra
@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        ([STARNBERG, "--planning-problem", "1"],
         "--planning-problem 1 is not in the file (its planning problems: none"),
        ([GUETERSLOH, "--planning-problem", "7"], "its planning problems: 1)"),
        ([GUETERSLOH, "--lanelet", "999", "--length-m", "200"],
         "--lanelet 999 is not in the file's lanelet network"),
        ([GUETERSLOH, "--lanelet", "84599", "--length-m", "156"],
         "the route branches within 156 m; name the branch by its lanelets, one of: "
         "84599,85214,84594"),
        ([GUETERSLOH, "--lanelet", "84591,84599", "--length-m", "200"], "not a chain"),
        # The planning problem's route is 113 m: no 2 s run at 30 m/s fits with its preview.
        ([GUETERSLOH, "--planning-problem", "1", "--speed-mps", "30"],
         "the route is 113 m long, a run at 30 m/s needs at least"),
        # An intersection turn of R ≈ 2–4 m: sharper than the truck's 5 m turning circle (the
        # road kind's own check, run on the written TOML before it is written).
        ([STARNBERG, "--lanelet", "96,24,92,2", "--length-m", "180", "--speed-mps", "5"],
         "is below the smallest allowed"),
    ],
)
def test_unusable_routes_exit_2_naming_the_problem(args, fragment: str, tmp_path: Path) -> None:
    _assert_refused(args, fragment, tmp_path)


@needs_extra
def test_import_writes_the_road_and_reports_what_it_measured(tmp_path: Path) -> None:
    out = tmp_path / "sub" / "road.toml"
    result = _run(GUETERSLOH, "--planning-problem", "1", "--vehicle", "car", "--speed-mps", "8",
                  "--out", str(out))
    assert result.exit_code == 0, result.output
    said = _said(result)
    assert "tightest bend R" in said and "own lane" in said and "3 obstacles" in said
    assert "dropped obstacle 30" in said  # the parked truck far off the route
    text = out.read_text()
    assert text.startswith("# Imported from CommonRoad DEU_Guetersloh-36_1_T-1.xml: planning "
                           "problem 1")
    # No underground label in the file: the camera's dry class value.
    assert "mu = 0.8" in text and "no underground label" in text


@needs_extra
@pytest.mark.parametrize(("label", "mu"), [("wet", 0.5), ("ice", 0.25), ("dirty", 0.8)])
def test_underground_label_sets_the_camera_class_value(label: str, mu: float,
                                                       tmp_path: Path) -> None:
    """A 2020a file's ``location/environment/underground`` gives μ (paper Table I's class value);
    ``--mu`` overrides it."""
    from mufusion.estimators.classes import PAPER_CLASSES

    assert mu in {c.value for c in PAPER_CLASSES}
    environment = ("<environment><time>08:30</time><timeOfDay>morning</timeOfDay>"
                   f"<weather>heavy_rain</weather><underground>{label}</underground>"
                   "</environment>\n  </location>")
    source = tmp_path / "labelled.xml"
    source.write_text(Path(GUETERSLOH).read_text().replace("</location>", environment, 1))
    out = tmp_path / "road.toml"
    result = _run(str(source), "--planning-problem", "1", "--vehicle", "car", "--speed-mps", "8",
                  "--out", str(out))
    assert result.exit_code == 0, result.output
    text = out.read_text()
    assert f"\nmu = {mu}\n" in text and f"underground '{label}'" in text
    result = _run(str(source), "--planning-problem", "1", "--vehicle", "car", "--speed-mps", "8",
                  "--mu", "0.3", "--out", str(out))
    assert result.exit_code == 0 and "\nmu = 0.3\n" in out.read_text()
