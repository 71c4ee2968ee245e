"""Component metadata files (rig_emulator/link/ftp/component_metadata.py).

The files are validated against mavlink's component_metadata/general.schema.json and
parameter.schema.json with the ``jsonschema`` package when the schema files are available:
set ``HILMS_MAVLINK_SCHEMAS`` to a directory holding them (from a checkout of
github.com/mavlink/mavlink, ``component_metadata/``); the project does not copy them in.
"""

import json
import os
from pathlib import Path

import pytest

from rig_emulator.link.ftp.component_metadata import (GENERAL_PATH, PARAMETERS_PATH, crc32, general_metadata,
                                                  metadata_files, parameter_metadata)
from rig_emulator.link.parameters.table import ParamTable

SCHEMAS = os.environ.get("HILMS_MAVLINK_SCHEMAS")


def test_every_parameter_is_described_with_unit_range_and_enums():
    doc = json.loads(parameter_metadata())
    entries = {p["name"]: p for p in doc["parameters"]}
    table = ParamTable()
    assert set(entries) == {p.name for p in table.params} and len(entries) == len(table)
    assert all(e["shortDesc"] and e["longDesc"] and e["type"] == "Float" for e in entries.values())
    assert [v["description"] for v in entries["CTL_STRATEGY"]["values"]] == ["smc-flc", "flc", "smc", "pid"]
    assert entries["CTL_STRATEGY"]["default"] == 0 and entries["CTL_STRATEGY"]["max"] == 3
    assert entries["SMC_K_PHI"]["units"] == "rad/s^2" and entries["SMC_K_PHI"]["default"] == 1.47
    assert entries["WP_RADIUS"]["default"] == 0.08 and entries["WP_RADIUS"]["max"] == 100
    assert entries["SIM_PHYS_HZ"]["rebootRequired"] is True
    assert [v["value"] for v in entries["MIS_ITEM0_HOME"]["values"]] == [0, 1]


def test_general_metadata_points_at_the_parameter_file_with_its_crc():
    general = json.loads(general_metadata())
    (entry,) = general["metadataTypes"]
    assert entry["type"] == 1 and entry["uri"] == "mftp:///" + PARAMETERS_PATH
    assert entry["fileCrc"] == crc32(parameter_metadata())
    assert set(metadata_files()) == {GENERAL_PATH, PARAMETERS_PATH}


@pytest.mark.skipif(not SCHEMAS, reason="HILMS_MAVLINK_SCHEMAS (mavlink's component_metadata/*.schema.json) not set")
@pytest.mark.parametrize("schema, build", [("general.schema.json", general_metadata),
                                           ("parameter.schema.json", parameter_metadata)])
def test_files_validate_against_the_mavlink_schema(schema, build):
    import jsonschema

    spec = json.loads((Path(SCHEMAS) / schema).read_text())
    jsonschema.validate(json.loads(build()), spec)
