"""A griffe extension for the API pages (mkdocs.yml): the project's docstrings use a few reST
forms that Markdown does not read; this turns them into Markdown before mkdocstrings renders.

* roles: ``:class:`~a.b.C```, ``:func:``, ``:mod:``, ``:meth:``, ``:attr:``, ``:data:`` -> `` `C` ``
  (``~``: the last part only);
* reST literals ````x```` -> `` `x` ``;
* doctest lines (``>>> ``, ``... ``) -> a fenced python block;
* a paragraph ending in ``::`` followed by an indented block -> the paragraph with ``:`` and a
  fenced block.
"""

from __future__ import annotations

import re
import textwrap

from griffe import Extension

ROLE = re.compile(r":(?:class|func|mod|meth|attr|data|obj|exc):`(~?)([^`]+)`")
LITERAL = re.compile(r"``([^`]+)``")


def _role(m: re.Match) -> str:
    target = m.group(2)
    return f"`{target.split('.')[-1] if m.group(1) else target}`"


def to_markdown(text: str) -> str:
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.lstrip().startswith(">>> "):
            block = []
            while i < len(lines) and lines[i].lstrip().startswith((">>> ", "... ")):
                block.append(lines[i].lstrip()[4:])
                i += 1
            out += ["", "```python", *block, "```", ""]
            continue
        if line.rstrip().endswith("::") and i + 1 < len(lines):
            j = i + 1
            while j < len(lines) and not lines[j].strip():
                j += 1
            indent = len(lines[j]) - len(lines[j].lstrip()) if j < len(lines) else 0
            base = len(line) - len(line.lstrip())
            if j < len(lines) and indent > base:
                head = line.rstrip()[:-2].rstrip()
                out.append(head + ":" if head.strip() else "")
                block = []
                while j < len(lines) and (not lines[j].strip() or len(lines[j]) - len(lines[j].lstrip()) > base):
                    block.append(lines[j])
                    j += 1
                while block and not block[-1].strip():
                    block.pop()
                out += ["", "```", *textwrap.dedent("\n".join(block)).split("\n"), "```", ""]
                i = j
                continue
        out.append(line)
        i += 1
    in_fence = False
    result = []
    for line in out:
        if line.startswith("```"):
            in_fence = not in_fence
        elif not in_fence:
            line = LITERAL.sub(r"`\1`", ROLE.sub(_role, line))
        result.append(line)
    return "\n".join(result)


class RstToMarkdown(Extension):
    def on_instance(self, *, obj, **kwargs) -> None:  # noqa: ARG002 - griffe's hook signature
        if obj.docstring is not None:
            obj.docstring.value = to_markdown(obj.docstring.value)
