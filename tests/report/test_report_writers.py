"""write_report / write_reports: the registry by suffix, atomic all-or-nothing writes."""

import json
import os

import pytest
from report_helpers import known_model

from asbuilt.errors import AsbuiltError, ExportError, UnknownFormatError
from asbuilt.report import SUFFIXES, report_format_for, write_report, write_reports


@pytest.mark.parametrize(
    ("name", "start"),
    [
        ("qa.html", "<!DOCTYPE html>"),
        ("qa.HTM", "<!DOCTYPE html>"),
        ("qa.csv", "id,type,"),
        ("qa.json", "{"),
    ],
)
def test_format_by_suffix(tmp_path, name, start):
    path = write_report(known_model(), tmp_path / name)
    assert path == tmp_path / name
    assert path.read_text(encoding="utf-8-sig").startswith(start)


def test_registry_lists_the_formats():
    assert set(SUFFIXES) == {".html", ".htm", ".csv", ".json"}
    assert report_format_for("x.Json").name == "JSON"


@pytest.mark.parametrize("name", ["qa.pdf", "qa"])
def test_unknown_suffix_names_the_file(tmp_path, name):
    with pytest.raises(UnknownFormatError) as info:
        write_report(known_model(), tmp_path / name)
    message = str(info.value)
    assert str(tmp_path / name) in message and ".html" in message
    assert isinstance(info.value, AsbuiltError) and "\n" not in message


def test_all_or_nothing(tmp_path):
    old = tmp_path / "qa.csv"
    old.write_text("old", encoding="utf-8")
    with pytest.raises(ExportError) as info:
        write_reports(known_model(), [tmp_path / "qa.html", old, tmp_path / "missing" / "x.json"])
    assert "missing" in str(info.value)
    assert not (tmp_path / "qa.html").exists()
    assert old.read_text(encoding="utf-8") == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["qa.csv"]  # no temporary files left


def test_same_output_twice(tmp_path):
    with pytest.raises(ExportError, match="given twice"):
        write_reports(known_model(), [tmp_path / "a.csv", tmp_path / "." / "a.csv"])


def test_unknown_option(tmp_path):
    with pytest.raises(TypeError, match="colour"):
        write_report(known_model(), tmp_path / "a.csv", colour="red")


def test_options_reach_their_writer(tmp_path):
    write_reports(
        known_model(), [tmp_path / "a.html", tmp_path / "a.json"], density=8000, figure_format="png"
    )
    document = json.loads((tmp_path / "a.json").read_text(encoding="utf-8"))
    assert document["takeoff"]["totals"]["density"] == 8000
    assert "data:image/png;base64," in (tmp_path / "a.html").read_text(encoding="utf-8")


def test_files_get_the_usual_permissions(tmp_path):
    mask = os.umask(0o022)
    try:
        path = write_report(known_model(), tmp_path / "a.csv")
    finally:
        os.umask(mask)
    assert path.stat().st_mode & 0o777 == 0o644
