"""Fixtures of the link tests: a rig served in a thread of the test process."""

import pytest

from rig_emulator.testing.rig import RigThread, connect


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a test that drives an external ground station (MAVProxy)")


@pytest.fixture
def rig():
    """A rig at 4x real time with a tcpin endpoint; ``rig.server`` exposes counters."""
    with RigThread(speedup=4.0) as r:
        yield r


@pytest.fixture
def client(rig):
    conn = connect(rig.tcp_url)
    yield conn
    conn.close()
