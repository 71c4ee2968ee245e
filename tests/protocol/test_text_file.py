"""read_text: a user's text file, or the caller's error naming the file, the line and why."""

import pytest

from protocol.mission_files import MissionFileError, load_mission
from protocol.text_file import read_text


def test_text_comes_back_and_bad_files_name_the_line(tmp_path):
    good = tmp_path / "a.txt"
    good.write_text("one\ntwo\n", encoding="utf-8")
    assert read_text(good, MissionFileError) == "one\ntwo\n"
    latin = tmp_path / "b.txt"
    latin.write_bytes(b"one\ntwo\n\xe9\n")
    with pytest.raises(MissionFileError, match=r"b.txt:3: not UTF-8 text"):
        read_text(latin, MissionFileError)
    binary = tmp_path / "c.plan"
    binary.write_bytes(b"{\n\x00\n")
    with pytest.raises(MissionFileError, match=r"c.plan:2: NUL byte: not a text file"):
        load_mission(binary)
    with pytest.raises(MissionFileError, match=r"cannot read"):
        read_text(tmp_path / "missing.txt", MissionFileError)
