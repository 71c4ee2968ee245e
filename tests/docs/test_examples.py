"""Every code example of README.md and docs/ runs, or says why it does not.

A fenced block in python, sh, bash or console is an example; the line before it is an HTML
comment (invisible on the rendered page) saying what to do with it:

* ``<!-- example: run -->``: run it in an empty directory (sh: with bash, ``set -e``, the
  environment's ``rig-emulator`` / ``rig-gcs`` first on PATH; python: as a script);
* ``<!-- example: with-rig -->``: the same with a served rig (the default plant, ``hilms``)
  reachable at the README's ``tcp:127.0.0.1:5760`` (the test substitutes the free port it
  started the rig on);
* ``<!-- example: pytest -->``: a test file run by pytest with the installed ``hilms_sil`` plug-in;
* ``<!-- example: skip (REASON) -->``: not run, for the reason given (it needs a ground
  station, serves until stopped, takes minutes, ...).

An unmarked example fails ``test_every_example_is_marked``: a new example either runs here or
says why not. The pages are the ones the site builds (docs/generated/ is code output, not examples).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LANGUAGES = {"python", "py", "sh", "bash", "console", "shell"}
MARK = re.compile(r"^<!--\s*example:\s*(run|with-rig|pytest|skip)\s*(\((?P<reason>.+)\))?\s*-->\s*$")
FENCE = re.compile(r"^(?P<indent>\s*)(?P<fence>```+|~~~+)\s*(?P<lang>[\w-]*)")
# a guard against a hung example, not a timed assertion: examples take seconds
EXAMPLE_TIMEOUT_S = 900


@dataclass
class Example:
    path: Path
    line: int  # 1-based line of the opening fence
    lang: str
    code: str
    mark: str | None
    reason: str | None

    @property
    def id(self) -> str:
        return f"{self.path.relative_to(ROOT)}:{self.line}"


#: pages the site does not build (mkdocs.yml exclude_docs): they are being replaced by new how-to pages
NOT_BUILT: set[str] = set()


def pages() -> list[Path]:
    docs = sorted(p for p in (ROOT / "docs").rglob("*.md")
                  if "generated" not in p.relative_to(ROOT / "docs").parts and p.name not in NOT_BUILT)
    return [ROOT / "README.md", *docs]


def examples(path: Path) -> list[Example]:
    lines = path.read_text().split("\n")
    found, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, lang, start = m.group("fence"), m.group("lang").lower(), i
        body = []
        i += 1
        while i < len(lines) and not lines[i].strip().startswith(fence):
            body.append(lines[i][len(m.group("indent")):])
            i += 1
        i += 1
        if lang not in LANGUAGES:
            continue
        prev = next((lines[j] for j in range(start - 1, -1, -1) if lines[j].strip()), "")
        mark = MARK.match(prev.strip())
        found.append(Example(path, start + 1, lang, "\n".join(body) + "\n", mark.group(1) if mark else None,
                             mark.group("reason") if mark else None))
    return found


ALL = [e for p in pages() for e in examples(p)]
RUNNABLE = [e for e in ALL if e.mark in ("run", "with-rig", "pytest")]


def test_every_example_is_marked():
    unmarked = [e.id for e in ALL if e.mark is None]
    assert not unmarked, ("examples without an <!-- example: run | with-rig | pytest | skip (REASON) --> line "
                          f"before them: {unmarked}")
    no_reason = [e.id for e in ALL if e.mark == "skip" and not (e.reason or "").strip()]
    assert not no_reason, f"skipped examples must say why: {no_reason}"


def test_there_are_runnable_examples():
    # the README's and the getting-started pages' examples at least: a parser that found none would pass everything
    assert {e.path.name for e in RUNNABLE} >= {"README.md", "first-flight.md", "first-controller.md", "first-fit.md"}


def _env() -> dict:
    bindir = str(Path(sys.executable).parent)
    env = dict(os.environ, PATH=bindir + os.pathsep + os.environ.get("PATH", ""), PYTHONUNBUFFERED="1",
               MPLBACKEND="Agg")
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def _shell(code: str) -> str:
    bindir = str(Path(sys.executable).parent)
    code = code.replace(".venv/bin/", bindir + "/").replace("bash scripts/", f"bash {ROOT}/scripts/")
    if code.lstrip().startswith("$ "):  # a console transcript: the commands only
        code = "\n".join(line[2:] for line in code.splitlines() if line.startswith("$ ")) + "\n"
    return "set -euo pipefail\n" + code


def _run(example: Example, cwd: Path, rig_url: str | None = None) -> subprocess.CompletedProcess:
    code = example.code
    if rig_url is not None:
        code = code.replace("tcp:127.0.0.1:5760", rig_url)
    if example.mark == "pytest":
        test_file = cwd / "test_example.py"
        test_file.write_text(code)
        cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(test_file)]
    elif example.lang in ("python", "py"):
        script = cwd / "example.py"
        script.write_text(code)
        cmd = [sys.executable, str(script)]
    else:
        cmd = ["bash", "-c", _shell(code)]
    return subprocess.run(cmd, cwd=cwd, env=_env(), capture_output=True, text=True, timeout=EXAMPLE_TIMEOUT_S)


@pytest.mark.parametrize("example", RUNNABLE, ids=[e.id for e in RUNNABLE])
def test_example_runs(example: Example, tmp_path):
    if example.mark == "with-rig":
        from rig_emulator.testing.rig import RigProcess, client_url

        # the default plant, as a user's `rig-emulator` serves it
        with RigProcess(speedup=5, airframe="hilms") as rig:
            done = _run(example, tmp_path, client_url(rig.tcp_url))
    else:
        done = _run(example, tmp_path)
    assert done.returncode == 0, (f"{example.id} exited {done.returncode}\n--- code\n{example.code}"
                                  f"--- stdout\n{done.stdout[-4000:]}\n--- stderr\n{done.stderr[-4000:]}")
