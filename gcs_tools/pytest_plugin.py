"""pytest fixtures for acceptance tests against a live rig (registered as the ``hilms_sil``
pytest11 plugin, or ``pytest_plugins = ["gcs_tools.pytest_plugin"]`` in a conftest).

* ``hilms_rig`` - a :class:`gcs_tools.api.RigSession` (rig on free ports, speed-up 20,
  logging to ``tmp_path / "run.tlog"``), closed after the test::

      def test_rectangle(hilms_rig):
          from gcs_tools.missions import rectangle_points
          hilms_rig.fly(rectangle_points(5, 3, 2))
          result = hilms_rig.finish()
          assert result.mean_errors["x_m"] < 0.15

  ``@pytest.mark.hilms_rig(speedup=10, rig_args=["--set", "control.strategy=\\"flc\\""])``
  changes how the rig is started.
"""

from __future__ import annotations

import pytest


def pytest_configure(config):
    config.addinivalue_line("markers", "hilms_rig(speedup=20, rig_args=(), log_rates=None): options of the hilms_rig fixture")


@pytest.fixture
def hilms_rig(request, tmp_path):
    from gcs_tools.api import RigSession

    marker = request.node.get_closest_marker("hilms_rig")
    kwargs = dict(marker.kwargs) if marker is not None else {}
    session = RigSession(log_path=tmp_path / "run.tlog", **kwargs)
    try:
        yield session
    finally:
        session.close()
