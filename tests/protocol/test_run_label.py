"""The run label a headless .tlog starts with (STATUSTEXT chunks) for plot titles."""


def test_a_long_run_label_goes_in_chunks_and_back():
    from protocol.run_label import CHUNK, label_chunks, label_from_texts, run_label

    label = run_label("hover-shocks", "smc-flc", "draganflyer", 2**63 - 1)
    chunks = label_chunks(label)
    assert len(chunks) == 2 and all(len(c) <= CHUNK for c in chunks)
    assert label_from_texts(["armed", "".join(chunks)]) == label
    assert label_from_texts(["armed"]) is None
