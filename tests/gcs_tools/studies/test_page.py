"""gcs_tools.studies.page: what a study prints becomes its docs page, under the command that made it
and the machine; every study offers --markdown."""

import importlib
import sys

import pytest

from gcs_tools.studies import STUDIES
from gcs_tools.studies.page import Page


def test_the_page_holds_what_was_printed_under_the_command(tmp_path, monkeypatch, capsys):
    target = tmp_path / "study-x.md"
    monkeypatch.setattr(sys, "argv", ["python -m gcs_tools.studies x", "scan", "--set", "a.b=[1, 2]",
                                      "--markdown", str(target)])
    page = Page(str(target), "What the table holds.", workers=2)
    page.print("| a | b |", "extra")
    page.print("plain text", md="| markdown | form |")
    page.print("terminal only", md="")
    page.page("page only")
    page.blank()
    page.print("| after | a blank |")
    assert not target.exists()  # written at the end, whole
    page.write()
    out = capsys.readouterr().out
    assert out.splitlines() == ["| a | b | extra", "plain text", "terminal only", "", "| after | a blank |"]
    head, body = target.read_text().split("\n\n", 1)
    assert head.startswith(f"Written by `python -m gcs_tools.studies x scan --set 'a.b=[1, 2]' --markdown {target}`: ")
    assert "with 2 worker processes on " in head and "load average" in head and head.endswith("What the table holds.")
    assert body == "| a | b | extra\n| markdown | form |\npage only\n\n| after | a blank |\n"


def test_without_a_file_nothing_is_written(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    page = Page(None)
    page.print("x")
    page.write()
    assert capsys.readouterr().out == "x\n"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", sorted(STUDIES))
def test_every_study_writes_markdown(name):
    parser = importlib.import_module(f"gcs_tools.studies.{STUDIES[name][0]}").parser()
    assert "--markdown" in parser._option_string_actions
    assert parser.prog == f"python -m gcs_tools.studies {name}"
