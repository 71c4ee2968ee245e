"""python -m gcs_tools.studies served-sysid: the page docs/how-to/identify.md includes (docs/generated/served-sysid.md).
Its flights are the served identification flight that tests/rig_emulator/link/commands/test_link_sysid.py flies;
here the table's form, from made-up results: one row per rate, each figure's range over its flights, the
interval's hits on the rig's delay counted, the model check's findings named."""

from gcs_tools.studies import served_sysid as ms
from rig_emulator.config.loader import load_config


def _result(rate, delay_s, bias, gain_off=0.0, findings=()):
    est = {"control.actuation_delay": {"value": delay_s, "lo": delay_s - 0.0005, "hi": delay_s + 0.0005},
           "motors.thrust_bias_grf": {"value": bias, "lo": bias - 3.0, "hi": bias + 3.0}}
    gains = load_config("hilms")["motors.thrust_gain"]
    for i in range(4):
        est[f"motors.thrust_gain[{i}]"] = {"value": gains[i] + (gain_off if i == 2 else 0.0)}
    for i in range(3):
        est[f"joint.cog_offset[{i}]"] = {"value": ms.COG[i] + (0.0002 if i == 1 else 0.0)}
    return {"rate_hz": rate, "speedup": 20.0 if rate == 100 else 2.0, "chunk_ms": 1.25 if rate == 100 else 0.5,
            "flight_wall_s": 60.0, "estimates": est, "findings": list(findings)}


def test_the_table_gives_each_rates_range_over_its_flights():
    flag = {"channel": "load cell 2", "t_from": 80.0, "t_to": 85.0, "ratio": 10.6, "limit": 8.0}
    results = [_result(100, 0.0134, -53.0, 0.01, [flag]), _result(500, 0.0130, -50.5),
               _result(100, 0.0124, -49.8), _result(500, 0.0129, -50.3, 0.002)]
    page = ms.markdown_page(results, "python -m gcs_tools.studies served-sysid --runs 2 --markdown F", "a machine")
    head, table = page.split("\n\n", 1)
    assert head.startswith("Written by `python -m gcs_tools.studies served-sysid --runs 2 --markdown F` on a machine")
    rows = [r.split(" | ") for r in table.splitlines()[2:]]
    assert [r[0] for r in rows] == ["| 100 Hz", "| 500 Hz"] and [r[2] for r in rows] == ["2", "2"]
    assert rows[0][3] == "12.4-13.4 ms" and rows[1][3] == "12.9-13.0 ms"
    assert rows[0][4] == "1 of 2" and rows[1][4] == "2 of 2"  # the rig runs 13 ms: 12.4 +- 0.5 misses it
    assert rows[0][5] == "0.0100" and rows[1][5] == "0.0020"
    assert rows[0][6] == "-53.0 to -49.8 gr.F" and rows[0][7] == "0.20 mm"
    assert rows[0][8] == "silent on 1 of 2; flags load cell 2 (10.6x) |" and rows[1][8] == "silent on 2 of 2 |"
