"""What run a log holds: scenario, strategy, airframe and seed, as one STATUSTEXT.

A headless ``.tlog`` (``rig-emulator simulate --out run.tlog``) starts with a STATUSTEXT
``run: scenario helix, strategy smc-flc, airframe hilms, seed 1`` (severity INFO, split into
MAVLink 2 chunks of 50 characters sharing one ``id`` when longer, as the STATUSTEXT
definition allows); ``rig-gcs plot`` puts the label in its titles. Both sides use this module.
"""

from __future__ import annotations

PREFIX = "run: "
CHUNK = 50  # STATUSTEXT.text


def run_label(scenario: str | None, strategy: str, airframe: str, seed: int) -> str:
    """``scenario helix, strategy smc-flc, airframe hilms, seed 1`` (no scenario part when None)."""
    head = f"scenario {scenario}, " if scenario else ""
    return f"{head}strategy {strategy}, airframe {airframe}, seed {seed}"


def label_chunks(label: str) -> list[str]:
    """The STATUSTEXT texts that carry ``label``, in order."""
    text = PREFIX + label
    return [text[i:i + CHUNK] for i in range(0, len(text), CHUNK)]


def label_from_texts(texts) -> str | None:
    """The run label among whole STATUSTEXT texts (chunks already joined), or None."""
    for text in texts:
        if text.startswith(PREFIX):
            return text[len(PREFIX):].strip()
    return None
