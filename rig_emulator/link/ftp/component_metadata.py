"""MAVLink component metadata of the rig (https://mavlink.io/en/services/component_information.html).

Two JSON files, served read-only over MAVFTP (:mod:`rig_emulator.link.ftp.server`):

* ``/metadata/general.json`` (COMP_METADATA_TYPE_GENERAL, mavlink's
  ``component_metadata/general.schema.json``): vendor, model, firmware version and the
  location and CRC32 of the parameter metadata. Its own location and CRC are what
  COMPONENT_METADATA (and the older COMPONENT_INFORMATION) carry.
* ``/metadata/parameters.json`` (COMP_METADATA_TYPE_PARAMETER, ``parameter.schema.json``,
  version 3): one entry per MAVLink parameter of the table (:mod:`rig_emulator.link.parameters.table`)
  with the schema's description, unit, range, default (the presets' value), enum values of
  text choices (``CTL_STRATEGY``: 0 smc-flc, 1 flc, 2 smc, 3 pid) and 0/1 of booleans,
  ``rebootRequired`` for the parameters fixed while the rig runs, and the schema section as
  the group. Every value is a REAL32 on the wire, so every ``type`` is ``Float``.

The CRC is zlib's CRC-32 of the file's bytes. The files are built once per process (they
depend on the schema and presets only, not on the running values).
"""

from __future__ import annotations

import functools
import json
import math
import zlib

from protocol.dialect import mavlink as M
from rig_emulator.config.loader import load_config
from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.link.telemetry import units as U

GENERAL_PATH = "metadata/general.json"
PARAMETERS_PATH = "metadata/parameters.json"
COMP_METADATA_TYPE_GENERAL = 0
COMP_METADATA_TYPE_PARAMETER = 1
FIRMWARE_VERSION = "0.1.0"  # pyproject's version
RESTART_ONLY = ("sim.physics_rate_hz", "sim.control_rate_hz", "sim.log_rate_hz")
_ELEMENT_NAMES = {"_PHI": "roll (phi)", "_THE": "pitch (theta)", "_PSI": "yaw (psi)", "_X": "X (east)",
                  "_Y": "Y (north)", "_Z": "Z (up)"}


def mftp_uri(path: str) -> str:
    """The MAVLink FTP URI of a file the autopilot component serves."""
    return "mftp:///" + path.lstrip("/")


def crc32(data: bytes) -> int:
    return zlib.crc32(data) & 0xFFFFFFFF


def _number(v: float):
    """A JSON number: integers stay integers, floats keep float32's precision."""
    v = float(v)
    return int(v) if v == int(v) and abs(v) < 2**31 else float(f"{v:.7g}")


def _entry(p, defaults) -> dict:
    spec = p.spec
    short = spec.doc.split(";")[0].split(":")[0].strip()
    suffix = p.name[len(p.name.rstrip("0123456789")):] if p.element is not None and p.name[-1].isdigit() else None
    if p.element is not None:
        label = next((v for k, v in _ELEMENT_NAMES.items() if p.name.endswith(k)), f"element {suffix or p.element + 1}")
        short = f"{short}: {label}"
    key = p.key if p.element is None else f"{p.key}[{p.element}]"
    entry = {"name": p.name, "type": "Float", "shortDesc": short[:120],
             "longDesc": f"{spec.doc} (rig parameter {key})", "group": p.key.split(".")[0]}
    if spec.unit:
        entry["units"] = spec.unit
    default = p.value(defaults)
    if math.isfinite(default):
        entry["default"] = _number(default)
    if spec.kind == "str":
        entry["values"] = [{"value": i, "description": c} for i, c in enumerate(spec.choices)]
        entry["min"], entry["max"] = 0, len(spec.choices) - 1
        entry["decimalPlaces"] = 0
    elif spec.kind == "bool":
        entry["values"] = [{"value": 0, "description": "off (false)"}, {"value": 1, "description": "on (true)"}]
        entry["min"], entry["max"] = 0, 1
        entry["decimalPlaces"] = 0
    else:
        if math.isfinite(spec.lo):
            entry["min"] = _number(spec.lo)
            if spec.lo_open:
                entry["longDesc"] += f"; must be greater than {spec.lo:g}"
        if math.isfinite(spec.hi):
            entry["max"] = _number(spec.hi)
    if p.key in RESTART_ONLY:
        entry["rebootRequired"] = True
    return entry


def _plugin_entry(p) -> dict:
    """A controller plug-in's parameter (:mod:`rig_emulator.link.parameters.plugin_params`)."""
    plugin = getattr(p.controller, "plugin_name", type(p.controller).__qualname__)
    what = p.param if p.element is None else f"{p.param}[{p.element}]"
    entry = {"name": p.name, "type": "Float", "shortDesc": p.spec.doc.split(";")[0][:120],
             "longDesc": f"{p.spec.doc} (parameter {what} of the controller plug-in {plugin})",
             "group": "controller plug-in", "default": _number(p.default())}
    if p.spec.unit:
        entry["units"] = p.spec.unit
    if math.isfinite(p.spec.lo):
        entry["min"] = _number(p.spec.lo)
    if math.isfinite(p.spec.hi):
        entry["max"] = _number(p.spec.hi)
    return entry


@functools.lru_cache(maxsize=4)
def parameter_metadata(controller=None) -> bytes:
    """``parameters.json`` (COMP_METADATA_TYPE_PARAMETER, version 3) for the whole table
    (with ``controller``: also the plug-in's own parameters, with its class defaults)."""
    defaults = load_config()
    entries = [_plugin_entry(p) if hasattr(p, "controller") else _entry(p, defaults)
               for p in ParamTable(controller).params]
    doc = {"version": 3, "parameters": entries}
    return json.dumps(doc, indent=1, sort_keys=False).encode("utf-8")


@functools.lru_cache(maxsize=4)
def general_metadata(controller=None) -> bytes:
    """``general.json`` (COMP_METADATA_TYPE_GENERAL) pointing at the parameter metadata."""
    params = parameter_metadata(controller)
    doc = {
        "version": 1,
        "vendorName": "hilms-sil",
        "modelName": "HILMS quadrotor motion simulator (emulated)",
        "firmwareVersion": FIRMWARE_VERSION,
        "metadataTypes": [
            {"type": COMP_METADATA_TYPE_PARAMETER, "uri": mftp_uri(PARAMETERS_PATH), "fileCrc": crc32(params)},
        ],
    }
    return json.dumps(doc, indent=1).encode("utf-8")


def metadata_files(controller=None) -> dict[str, bytes]:
    """Every file the rig serves over MAVFTP, by path (``controller``: the plug-in flying it)."""
    return {GENERAL_PATH: general_metadata(controller), PARAMETERS_PATH: parameter_metadata(controller)}


def _controller(ctx):
    return getattr(getattr(ctx, "rig", None), "controller", None)


# --- the messages that say where the files are (MAV_CMD_REQUEST_MESSAGE) ---------------------------------
def component_metadata_message(snap, ctx):
    """COMPONENT_METADATA: URI and CRC32 of the general metadata file."""
    return M.MAVLink_component_metadata_message(time_boot_ms=U.time_boot_ms(snap.stamp_us),
                                                file_crc=crc32(general_metadata(_controller(ctx))),
                                                uri=mftp_uri(GENERAL_PATH).encode("ascii"))


def component_information_message(snap, ctx):
    """COMPONENT_INFORMATION (deprecated form, for older ground stations): the same file, no peripherals."""
    return M.MAVLink_component_information_message(
        time_boot_ms=U.time_boot_ms(snap.stamp_us), general_metadata_file_crc=crc32(general_metadata(_controller(ctx))),
        general_metadata_uri=mftp_uri(GENERAL_PATH).encode("ascii"), peripherals_metadata_file_crc=0,
        peripherals_metadata_uri=b"")
