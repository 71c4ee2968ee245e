"""MkDocs hook: the pages' TeX (``$...$`` inline, ``$$ ... $$`` displayed) becomes MathML when the site is
built, so the equations render in any current browser with no script, web font or network access
(the site is read offline, from ``file://`` as well as from a server).

``pymdownx.arithmatex`` (generic mode, mkdocs.yml) finds the math in the Markdown and leaves it as
``<span class="arithmatex">\\(...\\)</span>`` / ``<div class="arithmatex">\\[...\\]</div>``; this hook
turns each into a ``<math>`` element with latex2mathml. A formula latex2mathml cannot read fails the
build and names the page and the formula, as a broken link does in strict mode.
"""

from __future__ import annotations

import html
import re

from latex2mathml.converter import convert

_INLINE = re.compile(r'<span class="arithmatex">\\\((.*?)\\\)</span>', re.S)
_BLOCK = re.compile(r'<div class="arithmatex">\\\[(.*?)\\\]</div>', re.S)
_UNKNOWN = re.compile(r">(\\[A-Za-z]+)<")
_OPEN = re.compile(r"(?<!\\){")
_CLOSE = re.compile(r"(?<!\\)}")


class MathError(ValueError):
    pass


def _mathml(tex: str, display: str, where: str) -> str:
    tex = html.unescape(tex).strip()
    try:
        out = convert(tex, display=display)
    except Exception as e:  # latex2mathml raises its own exception types and plain ones
        raise MathError(f"{where}: cannot render the formula {tex!r}: {type(e).__name__} {e}") from e
    # what latex2mathml lets through: a command it does not know stays as text, an open brace is closed silently
    unknown = _UNKNOWN.search(out)
    if unknown:
        raise MathError(f"{where}: the formula {tex!r} uses {unknown.group(1)!r}, which latex2mathml does not know")
    if len(_OPEN.findall(tex)) != len(_CLOSE.findall(tex)):
        raise MathError(f"{where}: the formula {tex!r} has unbalanced braces")
    # the TeX stays with the formula (MathML's annotation), for copy and paste and for readers without MathML
    head, rest = out.split(">", 1)
    body = rest[: -len("</math>")]
    return (f'{head}><semantics><mrow>{body}</mrow><annotation encoding="application/x-tex">{html.escape(tex)}'
            "</annotation></semantics></math>")


def render(text: str, where: str = "page") -> str:
    """Replace arithmatex's generic output in the HTML ``text`` by MathML."""
    text = _BLOCK.sub(lambda m: '<div class="math-block">' + _mathml(m.group(1), "block", where) + "</div>", text)
    return _INLINE.sub(lambda m: _mathml(m.group(1), "inline", where), text)


def on_page_content(html_text: str, page, config, files) -> str:  # noqa: ARG001 (MkDocs' hook signature)
    from mkdocs.exceptions import PluginError  # MkDocs prints it as one line and stops the build

    try:
        return render(html_text, page.file.src_uri)
    except MathError as e:
        raise PluginError(str(e)) from e
