"""The MAVLink parameter microservice on the rig's parameter table.

* PARAM_REQUEST_LIST: every parameter, indexes 0..count-1, to the requesting peer.
* PARAM_REQUEST_READ: by index (>= 0) or by name; unknown ones get a STATUSTEXT.
* PARAM_SET: validated against the schema through :meth:`LiveRig.set_param`; accepted
  changes act on the running controller at the next step and are echoed with PARAM_VALUE
  to every peer; rejected ones are answered with PARAM_VALUE holding the unchanged value
  plus a STATUSTEXT saying why. With a ``store`` (:mod:`rig_emulator.link.parameters.store`)
  an accepted change is stored before it is echoed; one that cannot be stored is undone
  and answered like a rejected one.
* A controller plug-in's own parameters (:mod:`.plugin_params`) are in the table after the
  rig's when the server's table was built with the plug-in; they are validated by the
  plug-in's rules and stored under its name.
* A derived parameter (:class:`~rig_emulator.link.parameters.table.DerivedParam`, e.g.
  MPC_THR_HOVER) is read from the running rig; a PARAM_SET of it is refused with the reason.
"""

from __future__ import annotations

from protocol.dialect import mavlink
from rig_emulator.config.loader import ConfigError
from rig_emulator.controllers.base import PluginError
from rig_emulator.link.parameters.table import Param, ParamTable, as_float32
from rig_emulator.link.state.directory import StateWriteError


class ParamService:
    def __init__(self, rig, out, table: ParamTable | None = None, store=None):
        self.rig = rig
        self.out = out  # reply(channel, msg), broadcast(msg), statustext(channel, severity, text)
        self.table = table or ParamTable()
        self.store = store  # save(name, value) before the echo, or None
        self.rejected = 0

    def value_message(self, p: Param):
        value = p.value_of(self.rig, self.out) if getattr(p, "read_only", False) else p.value(self.rig.cfg)
        return mavlink.MAVLink_param_value_message(
            param_id=p.name.encode("ascii"), param_value=as_float32(value),
            param_type=mavlink.MAV_PARAM_TYPE_REAL32, param_count=len(self.table), param_index=p.index)

    def request_list(self, msg, channel) -> None:
        for p in self.table.params:
            self.out.reply(channel, self.value_message(p))

    def request_read(self, msg, channel) -> None:
        p = self.table.lookup(msg.param_id, msg.param_index)
        if p is None:
            what = f"index {msg.param_index}" if msg.param_index >= 0 else f"{msg.param_id!r}"
            self.out.statustext(channel, mavlink.MAV_SEVERITY_WARNING, f"no parameter {what}")
            return
        self.out.reply(channel, self.value_message(p))

    def set(self, msg, channel) -> None:
        p = self.table.lookup(msg.param_id, -1)
        if p is None:
            self.rejected += 1
            self.out.statustext(channel, mavlink.MAV_SEVERITY_WARNING, f"no parameter {msg.param_id!r}")
            return
        if getattr(p, "read_only", False):
            self.rejected += 1
            self.out.reply(channel, self.value_message(p))
            self.out.statustext(channel, mavlink.MAV_SEVERITY_ERROR, f"{p.name} rejected: {p.name} is read-only")
            return
        old = self.rig.cfg[p.key]
        try:
            self.rig.set_param(p.key, p.to_config(float(msg.param_value), self.rig.cfg))
            if self.store is not None:
                plugin = getattr(p.controller, "plugin_name", None) if hasattr(p, "controller") else None
                try:
                    self.store.save(p.name, float(msg.param_value), plugin=plugin)
                except StateWriteError:
                    self.rig.set_param(p.key, old)
                    raise
        except (ConfigError, ValueError, PluginError) as exc:
            self.rejected += 1
            self.out.reply(channel, self.value_message(p))
            self.out.statustext(channel, mavlink.MAV_SEVERITY_ERROR, f"{p.name} rejected: {exc}")
            return
        self.out.broadcast(self.value_message(p))
