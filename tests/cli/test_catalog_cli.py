"""``asbuilt catalog list`` and ``asbuilt catalog show NAME``: tables, JSON, errors (exit 2)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from asbuilt.catalog import catalog_names
from asbuilt.cli import main


def test_list_names_every_catalog(capsys):
    assert main(["catalog", "list"]) == 0
    out = capsys.readouterr().out
    for name in catalog_names():
        assert name in out


def test_list_json(capsys):
    assert main(["catalog", "list", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    by_name = {row["name"]: row for row in rows}
    assert by_name["asme-b36.10m"]["kind"] == "pipe" and by_name["asme-b36.10m"]["sizes"] == 36
    assert by_name["asme-b16.9"]["kind"] == "fittings"


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("asme-b36.10m", ["NPS", "114.3", "6.02", "STD", "XXS"]),
        ("asme-b16.9", ["elbow90_lr", "152", "105"]),
        ("en-10220", ["DN", "76.1"]),
        ("astm-b88", ["CTS", "28.575"]),
    ],
)
def test_show_table_in_millimetres(capsys, name, expected):
    assert main(["catalog", "show", name]) == 0
    out = capsys.readouterr().out
    for text in expected:
        assert text in out


def test_show_json_round_trips_the_data(capsys):
    assert main(["catalog", "show", "asme-b36.10m", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    four = next(s for s in doc["sizes"] if s["nominal"] == "4")
    assert four["od"] == 114.3 and four["walls"]["STD"] == 6.02 and four["dn"] == 100
    assert all(s["source"] for s in doc["sizes"])


def test_show_a_user_file(tmp_path, capsys):
    path = tmp_path / "mine.csv"
    path.write_text("# name: mine\n# kind: pipe\n# units: in\nnominal,od,source\n4,4.5,me\n")
    assert main(["catalog", "show", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["sizes"][0]["od"] == pytest.approx(114.3)


def test_unknown_and_malformed_catalogs_exit_2_with_one_line(tmp_path, capsys):
    assert main(["catalog", "show", "nope"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown catalog 'nope'" in err
    bad = tmp_path / "bad.csv"
    bad.write_text("# name: bad\n# kind: pipe\n# units: mm\nnominal,od,source\n4,x,me\n")
    assert main(["catalog", "show", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}: line 5, column 'od'" in err and err.count("\n") == 1


def test_no_action_is_a_usage_error(capsys):
    assert main(["catalog"]) == 2
    assert "asbuilt catalog" in capsys.readouterr().err


def test_subprocess():
    done = subprocess.run(
        [sys.executable, "-m", "asbuilt", "catalog", "list", "--json"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0
    assert "asme-b36.10m" in done.stdout
