"""`python -m benchmarks.plugin_share --markdown FILE`: the page docs/explanation/controller-speed.md
includes (docs/generated/plugin-share.md) says how it was made and holds one row a case. Flown with
the built-in alone and short flights: the page's form is tested, not the machine's speed."""

from benchmarks import plugin_share


def test_markdown_page_names_the_command_machine_and_every_case(tmp_path, monkeypatch):
    page = tmp_path / "share.md"
    argv = ["--duration", "0.2", "--repeat", "2", "--cases", "builtin-pid", "--markdown", str(page)]
    monkeypatch.setattr("sys.argv", ["plugin_share.py", *argv])
    assert plugin_share.main(argv) == 0
    text = page.read_text()
    head, table = text.split("\n\n", 1)
    assert head.startswith("Written by `python -m benchmarks.plugin_share --duration 0.2 --repeat 2 "
                           "--cases builtin-pid --markdown ")
    assert "load average" in head and "Python 3." in head and "us of CPU" in head
    rows = [ln for ln in table.splitlines() if ln.startswith("| `")]
    assert len(rows) == 1 and rows[0].startswith("| `builtin-pid` | the built-in `pid` strategy")
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    assert cells[2].endswith("x") and float(cells[3][:-1]) > 0.0
    assert cells[4] == "1.00 (1.00-1.00)" and cells[5] == "-"
