"""The docs' equations hook (scripts/mkdocs_mathml.py): TeX in the pages becomes MathML at build time,
and a formula it cannot render stops the build with the page and the formula named."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("mkdocs_mathml", ROOT / "scripts" / "mkdocs_mathml.py")
mathml = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mathml)


def test_inline_and_block_become_mathml_with_their_tex():
    page = ('<p>friction <span class="arithmatex">\\(c_v \\omega &lt; \\tau\\)</span> here</p>\n'
            '<div class="arithmatex">\\[\nI\\,\\dot{\\boldsymbol\\omega} = \\frac{a}{b}\n\\]</div>')
    out = mathml.render(page, "x.md")
    assert "arithmatex" not in out
    inline, block = re.findall(r"<math [^>]*>.*?</math>", out, re.S)
    assert 'display="inline"' in inline and 'display="block"' in block
    assert out.count('<div class="math-block">') == 1
    # the HTML-escaped TeX is unescaped before conversion, and kept (escaped again) as the annotation
    assert "<mo>&#x0003C;</mo>" in inline
    assert '<annotation encoding="application/x-tex">c_v \\omega &lt; \\tau</annotation>' in inline
    assert "<mfrac>" in block and "<mover>" in block
    assert out.startswith("<p>friction <math") and "</math> here</p>" in out


@pytest.mark.parametrize("tex, says", [
    ("\\foo x", "uses '\\\\foo'"),          # latex2mathml would print the command as text
    ("\\frac{a", "unbalanced braces"),      # and close the brace silently
    ("x^", "MissingSuperScriptOrSubscriptError"),
    ("\\left( x", "ExtraLeftOrMissingRightError"),
])
def test_a_formula_it_cannot_render_names_the_page_and_the_formula(tex, says):
    with pytest.raises(mathml.MathError) as e:
        mathml.render(f'<span class="arithmatex">\\({tex}\\)</span>', "explanation/rig.md")
    msg = str(e.value)
    assert msg.startswith("explanation/rig.md: ") and repr(tex) in msg and says in msg


def test_text_without_math_is_left_alone():
    page = "<p>a price of $5 and <code>$x$</code></p>"
    assert mathml.render(page) == page


def test_the_site_is_built_with_the_hook():
    cfg = (ROOT / "mkdocs.yml").read_text()
    assert "scripts/mkdocs_mathml.py" in cfg and "generic: true" in cfg
    pages = [p for p in (ROOT / "docs").rglob("*.md") if "$$" in p.read_text()]
    assert {p.name for p in pages} >= {"rig.md", "hardware-effects.md", "stability.md"}
