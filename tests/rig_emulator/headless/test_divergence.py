"""The onboard position against the physics vehicle (SIM_STATE): the figures of a run, the served
rig's once-per-episode report, and the virtual ground's resting contact seen in both positions."""

import math
from types import SimpleNamespace

import numpy as np

from rig_emulator.api import simulate
from rig_emulator.headless.divergence import DivergenceWatch, divergence_stats


def _fake_rig(onboard, physics, threshold=1.0, estimated=True):
    """What DivergenceWatch reads of a LiveRig: the config, the sensing's onboard state, the physics state."""
    state = SimpleNamespace(onboard=np.array([*onboard, 0.0, 0.0, 0.0]))
    sensing = SimpleNamespace(params=SimpleNamespace(estimated=estimated), state=state)
    x = np.zeros(17)
    x[0:3] = physics
    return SimpleNamespace(cfg={"estimation.divergence_warning_m": threshold}, sim=SimpleNamespace(sensing=sensing, x=x))


def test_the_divergence_report_fires_once_above_the_threshold_and_not_below():
    watch = DivergenceWatch()
    rig = _fake_rig((0.0, 0.0, 0.9), (0.0, 0.0, 0.0))
    assert watch.poll(rig) is None  # 0.9 m: under 1 m
    rig.sim.sensing.state.onboard[0:3] = (0.3, 1.2, 2.0)  # 2.35 m apart
    text = watch.poll(rig)
    assert text is not None and "2.4 m apart" in text and "N +1.2 E +0.3 D -2.0" in text
    assert watch.poll(rig) is None  # the same episode: said once
    rig.sim.sensing.state.onboard[0:3] = (0.0, 0.0, 0.6)  # back under 1 m but not under half of it
    assert watch.poll(rig) is None
    rig.sim.sensing.state.onboard[0:3] = (0.0, 0.0, 1.5)
    assert watch.poll(rig) is None  # still the same episode
    rig.sim.sensing.state.onboard[0:3] = (0.0, 0.0, 0.4)  # within half: the episode is over
    assert watch.poll(rig) is None
    rig.sim.sensing.state.onboard[0:3] = (0.0, 0.0, 1.1)
    assert watch.poll(rig) is not None and watch.reports == 2
    assert DivergenceWatch().poll(_fake_rig((0.0, 0.0, 5.0), (0.0, 0.0, 0.0), threshold=0.0)) is None  # 0 = never
    assert DivergenceWatch().poll(_fake_rig((0.0, 0.0, 5.0), (0.0, 0.0, 0.0), estimated=False)) is None


def test_divergence_stats_of_a_series():
    t = np.arange(0.0, 60.0, 0.01)
    pos_true = np.zeros((t.size, 3))
    pos = np.zeros((t.size, 3))
    pos[:, 2] = 0.01 * t ** 2  # onboard climbs, the physics vehicle stays on the ground
    pos_true[:, 0] = np.where(t < 1.0, 0.0, t - 1.0)  # ... and slides along it after 1 s
    st = divergence_stats({"t": t, "pos": pos, "pos_true": pos_true}, 1.0)
    assert math.isclose(st.first_over_s, 2.0, abs_tol=0.02)  # sqrt((t - 1)^2 + (0.01 t^2)^2) > 1
    n, e, d = st.at[30.0]
    assert (n, e) == (0.0, -29.0) and math.isclose(d, -9.0)
    assert 60.0 in st.at  # the last row is a log period before the end
    assert math.isclose(st.slid_physics_m, t[-1] - 1.0, rel_tol=1e-9) and st.slid_onboard_m == 0.0


def test_a_grounded_vehicle_does_not_slide_headless():
    """The harmonic attitude scenario (Eq. 44, 10 deg roll) flies attitude only, at the hover thrust the
    controllers compute: on the hardware rig (the default plant) both vehicles stand on the ground most of
    the time with the rig tilted. Standing there neither moves; the ideal plant's frictionless reading of
    the ground, set on the same plant, slides them metres."""
    held = simulate("harmonic", duration=10.0, seed=2)
    assert held.config["sim.ground_contact"] == "hold"
    st = divergence_stats(held.series, 1.0)
    assert st.grounded_physics_s > 5.0
    assert st.slid_onboard_m == 0.0 and st.slid_physics_m == 0.0
    slid = divergence_stats(simulate("harmonic", duration=10.0, seed=2,
                                     overrides={"sim.ground_contact": "frictionless"}).series, 1.0)
    assert slid.slid_physics_m > 0.5


def test_the_divergence_command_prints_both_plants(capsys):
    from rig_emulator.cli import main

    assert main(["divergence", "--scenario", "hover", "--duration", "2", "--seed", "3"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split()[:3] for line in lines] == [["hover", "hilms", "3"], ["hover", "hilms-ideal", "3"]]
    assert all("max" in line and "rms" in line and "slid on ground" in line for line in lines)


def test_the_divergence_command_writes_its_table(tmp_path, capsys, monkeypatch):
    from rig_emulator.cli import main

    page = tmp_path / "divergence.md"
    argv = ["divergence", "--scenario", "hover", "--duration", "2", "--seed", "3", "--at", "1", "5",
            "--markdown", str(page)]
    monkeypatch.setattr("sys.argv", ["rig-emulator", *argv])
    assert main(argv) == 0
    printed = capsys.readouterr().out.strip().splitlines()
    head, table = page.read_text().split("\n\n", 1)
    assert head.startswith(f"Written by `rig-emulator divergence --scenario hover --duration 2 --seed 3 --at 1 5 "
                           f"--markdown {page}`")
    rows = [r.strip("|").split("|") for r in table.splitlines()]
    assert [c.strip() for c in rows[0]] == ["scenario", "plant", "max", "rms", "over 1 m from", "at 1 s (N, E, D)",
                                            "at 5 s (N, E, D)"]
    # both plants: the command compares the hardware rig with the ideal plant unless --airframe says otherwise
    assert [[c.strip() for c in r[:2]] for r in rows[2:]] == [["hover", "hilms"], ["hover", "hilms-ideal"]]
    for r, line in zip(rows[2:], printed):  # the figures the command printed
        assert f"max {float(r[2].split()[0]):6.2f} m" in line
        assert r[5].count(",") == 2 and r[6].strip() == ""  # a vector at 1 s; the 2 s run ends before 5 s
