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

import functools
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


# --- every command the pages quote exists ----------------------------------------------------------
#
# A page that quotes `python scripts/gone.py`, `python -m gcs_tools.studies gone`, `rig-gcs gone`, an
# option a command no longer has or a file of the repository that is gone sends its reader to an
# error. The commands are read from the code spans and code blocks of every page (the generated ones
# too) and checked against the files and the argument parsers; nothing is run.

#: a file of the repository named in the text (`scripts/docs_gen.py`, `docs/how-to/faults.md`, ...)
REPO_FILE = re.compile(r"(?<![\w/.-])(?:scripts|docs|rig_emulator|gcs_tools|protocol|benchmarks|tests)/"
                       r"[\w/.-]+\.(?:py|sh|md|toml|json|xml)\b")
PLACEHOLDER = re.compile(r"(?<![A-Za-z])(?:NAME|FILE|DIR|PLANT)(?![A-Za-z])")  # `exp_NAME.py`: any experiment
INLINE = re.compile(r"(?<!`)`([^`\n]+)`(?!`)")
NUMBER = re.compile(r"^-?\d")


def _all_pages() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def _code(path: Path) -> list[tuple[int, str]]:
    """(line, text) of every code span and every line of every code block of a page (a line ending
    in a backslash joined to the next)."""
    out, fence, pending = [], None, None
    for i, line in enumerate(path.read_text().split("\n"), 1):
        m = FENCE.match(line)
        if fence is None and m:
            fence = m.group("fence")
            continue
        if fence is not None:
            if line.strip().startswith(fence):
                fence = None
                continue
            start, text = pending if pending else (i, "")
            text += " " + line
            pending = (start, text[:-1]) if line.rstrip().endswith("\\") else None
            if pending is None:
                out.append((start, text))
            continue
        out += [(i, m.group(1)) for m in INLINE.finditer(line)]
    return out


def _tokens(text: str) -> list[str]:
    import shlex

    try:
        return shlex.split(text, comments=True)
    except ValueError:  # an unbalanced quote in prose-like code: words are enough here
        return text.split()


def _commands(text: str):
    """(kind, words after the program) of each command in one code span or line."""
    for part in re.split(r"&&|\|\||;|\|(?!\s*\w+=)|\$\(", text):
        words = [w.strip("[]") for w in _tokens(part)]
        for i, w in enumerate(words):
            prog = w.rsplit("/", 1)[-1]
            if prog in ("rig-gcs", "rig-emulator"):
                yield prog, words[i + 1:]
                break
            if prog in ("python", "python3") and words[i + 1:i + 2] == ["-m"] and i + 2 < len(words):
                yield "python -m", words[i + 2:]
                break


def _options(parser) -> set[str]:
    return set(parser._option_string_actions)


def _check_options(parser, words: list[str], where: str) -> list[str]:
    known = _options(parser)
    bad = []
    for w in words:
        if w.startswith("-") and not NUMBER.match(w) and w != "-" and "..." not in w:
            name = w.split("=", 1)[0]
            if name not in known:
                bad.append(f"{where}: `{parser.prog}` has no option {name}")
    return bad


def _walk(parser, words: list[str], where: str) -> list[str]:
    """Descend ``words`` through ``parser``'s sub-commands (or its first positional's choices, as in
    ``rig-gcs mission upload`` and ``python -m gcs_tools.studies table6 candidates``); check the
    names and the options."""
    sub = _subparsers(parser)
    choice = next((a for a in parser._actions if not a.option_strings and a.choices), None)
    if words and not words[0].startswith("-") and not words[0].isupper():  # upper case: a placeholder
        name = words[0]
        if sub is not None:
            if name not in sub.choices:
                return [f"{where}: `{parser.prog}` has no sub-command {name!r}"]
            return _walk(sub.choices[name], words[1:], where)
        if choice is not None and name not in choice.choices:
            return [f"{where}: `{parser.prog}` has no {choice.dest} {name!r} (choose from "
                    f"{', '.join(map(str, choice.choices))})"]
    return _check_options(parser, words, where)


def _subparsers(parser):
    import argparse

    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action
    return None


@functools.lru_cache(maxsize=None)
def _parsers() -> dict:
    from gcs_tools.cli import build_parser as gcs_parser
    from rig_emulator.cli import build_parser as rig_parser

    return {"rig-gcs": gcs_parser(), "rig-emulator": rig_parser()}


@functools.lru_cache(maxsize=None)
def _study_parser(name: str):
    import importlib

    from gcs_tools.studies import STUDIES

    return importlib.import_module(f"gcs_tools.studies.{STUDIES[name][0]}").parser()


@functools.lru_cache(maxsize=None)
def _benchmarks() -> tuple:
    from benchmarks.cli import build_parser
    from benchmarks.suite import REGISTRY

    return build_parser(), set(REGISTRY.benchmarks)


def _check_benchmarks(words: list[str], where: str) -> list[str]:
    """``python -m benchmarks``' options and the names ``--only`` selects."""
    parser, names = _benchmarks()
    bad = _check_options(parser, words, where)
    for opt, value in zip(words, words[1:]):
        if opt == "--only":
            bad += [f"{where}: no benchmark {n!r} (`python -m benchmarks --only {n}`)"
                    for n in value.split(",") if n and not n.isupper() and n not in names]
    return bad


@functools.lru_cache(maxsize=None)
def _module_exists(module: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(module.split(".")[0]) is not None and importlib.util.find_spec(module) is not None


def _stale_commands(path: Path) -> list[str]:
    from gcs_tools.studies import STUDIES

    parsers = _parsers()
    rel = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path.name
    bad = [f"{rel}: {m.group(0)} does not exist" for m in REPO_FILE.finditer(path.read_text())
           if not (ROOT / m.group(0)).is_file() and not PLACEHOLDER.search(m.group(0))]
    for line, text in _code(path):
        where = f"{rel}:{line}"
        for kind, words in _commands(text):
            if kind == "rig-emulator" and words and words[0].startswith("-"):
                words = ["serve", *words]  # `rig-emulator [options]` serves
            if kind in parsers:
                bad += _walk(parsers[kind], words, where)
                continue
            if not words or not re.fullmatch(r"[A-Za-z_][\w.]*", words[0]):
                continue
            module = words[0]
            if not _module_exists(module):
                bad.append(f"{where}: no module {module} (`python -m {module}`)")
                continue
            if module == "benchmarks":
                bad += _check_benchmarks(words[1:], where)
            if module == "gcs_tools.studies" and len(words) > 1 and not words[1].startswith("-") \
                    and not words[1].isupper():  # `python -m gcs_tools.studies NAME`: a placeholder
                name = words[1]
                if name not in STUDIES:
                    bad.append(f"{where}: no study {name!r} (`python -m gcs_tools.studies {name}`)")
                    continue
                bad += _walk(_study_parser(name), words[2:], where)
    return bad


def test_quoted_commands_exist():
    bad = [msg for p in _all_pages() for msg in _stale_commands(p)]
    assert not bad, "the docs quote commands that do not exist:\n" + "\n".join(bad)


def test_quoted_command_check_finds_stale_ones(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("\n".join([
        "Run `python scripts/gone_study.py point` or `rig-gcs reproduce -o DIR --plant hilms`; see "
        "docs/GONE.md, not docs/how-to/faults.md or gcs_tools/reproduce/exp_NAME.py.",
        "```sh",
        "rig-gcs reproduce -o out --no-such-option",
        "rig-emulator gone-command --seed 0",
        "rig-emulator --speedup 5 --not-a-serve-option  # plain rig-emulator serves",
        "rig-gcs mission upload tcp:127.0.0.1:5760 rect.plan && rig-gcs mission gone x",
        "python -m gcs_tools.studies gone-study",
        "python -m gcs_tools.studies table6 gone-table --workers 2",
        "python -m gcs_tools.studies paper-numbers point \\",
        "    --not-an-option 3",
        "python -m benchmarks.gone_probe",
        "python -m benchmarks --only gone-bench --repeat 3",
        "```",
        "`python -m gcs_tools.studies chattering --delay-scan --seeds 3` and `rig-emulator params --airframe hilms`",
    ]) + "\n")
    found = "\n".join(_stale_commands(page))
    for stale in ("scripts/gone_study.py", "docs/GONE.md", "--no-such-option", "'gone-command'", "--not-a-serve-option",
                  "'gone'", "'gone-study'", "'gone-table'", "--not-an-option", "benchmarks.gone_probe",
                  "'gone-bench'"):
        assert stale in found, (stale, found)
    assert len(found.splitlines()) == 11, found  # the commands that exist are not reported
