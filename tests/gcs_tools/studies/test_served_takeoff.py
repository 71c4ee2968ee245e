"""python -m gcs_tools.studies served-takeoff: the served take-off docs/explanation/sim-state.md quotes (its page,
docs/generated/served-takeoff.md). One short served take-off over a real socket, and the page's form."""

import pytest

from gcs_tools.studies import served_takeoff as mg


@pytest.fixture(scope="module")
def takeoff():
    return mg.fly_once("hold", 3.0, 0, quiet=True)


def test_a_served_takeoff_leaves_the_ground_and_is_measured(takeoff):
    onboard, physics = takeoff["onboard"], takeoff["physics"]
    assert onboard["left_s"] is not None and 0.0 < onboard["left_s"] < 2.0
    assert onboard["max_m"] < 0.2 and onboard["end_ned"][2] < -0.3  # climbing over home
    assert physics["max_m"] >= physics["on_ground_max_m"] >= 0.0


def test_the_page_gives_ranges_per_contact_and_vehicle(takeoff):
    other = {k: dict(v, max_m=v["max_m"] + 0.5, left_s=None if k == "physics" else v["left_s"])
             for k, v in takeoff.items()}
    text = mg.markdown({"hold": [takeoff, other], "frictionless": [takeoff]},
                       "python -m gcs_tools.studies served-takeoff --runs 2 --markdown F", "a machine", 3.0, 0)
    head, table = text.split("\n\n", 1)
    assert head.startswith("Written by `python -m gcs_tools.studies served-takeoff --runs 2 --markdown F` on a machine")
    rows = [r for r in table.splitlines() if r.startswith("| `")]
    assert [r.split("|")[1:3] for r in rows] == [[" `hold` ", " onboard (LOCAL_POSITION_NED) "],
                                                [" `hold` ", " physics (SIM_STATE) "],
                                                [" `frictionless` ", " onboard (LOCAL_POSITION_NED) "],
                                                [" `frictionless` ", " physics (SIM_STATE) "]]
    o = takeoff["onboard"]
    assert f"| {o['max_m']:.3f}-{o['max_m'] + 0.5:.3f} |" in rows[0]  # a range over the two runs
    assert "(1 never)" in rows[1]
