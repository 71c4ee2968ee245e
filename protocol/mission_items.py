"""MAVLink mission items <-> the rig's mission: frames, home conversion, validation.

Shared by the rig's mission server (``rig_emulator/link/mission/``) and the ground tools
(``gcs_tools/``), so both read a mission item the same way.

Item 0 (the lead's decision)
----------------------------
The rig follows the PX4/MAVSDK convention: **every uploaded item, item 0 included, is a
mission item and is flown**; the home position is separate (HOME_POSITION). With the rig
parameter ``MIS_ITEM0_HOME = 1`` the rig follows ArduPilot's convention instead, for
MAVProxy users whose ``wp load`` uploads line 0 of a QGC WPL 110 file (ArduPilot's home
line) as item 0: item 0 is then stored and returned on download but not flown, and it does
not move the rig's home. The ground tools (``rig-gcs``) read WPL line 0 as home and upload
lines 1..N as items, so they agree with the default (``MIS_ITEM0_HOME = 0``).
:func:`mission_plan` takes the choice as ``item0_home``.

Items
-----
:class:`MissionItem` holds one item as MISSION_ITEM/MISSION_ITEM_INT carry it, with ``x``
and ``y`` in natural units: degrees for the global frames, metres for the local frames,
the raw parameter value for commands without a position. MISSION_ITEM_INT scales them by
1e7 (global) or 1e4 (local, as PX4 does); :func:`item_from_message` undoes the scaling and
:func:`item_to_int_message` / :func:`item_to_float_message` apply it, so an item uploaded in
one form is downloaded identical in that form (and NaN, which MISSION_ITEM_INT cannot carry,
becomes 0).

Supported commands (anything else: ``MAV_MISSION_UNSUPPORTED``):

* ``MAV_CMD_NAV_WAYPOINT``: param1 hold time (s, >= 0; NaN = 0), param2 acceptance radius
  (m, >= 0; 0 or NaN = the rig's switching-radius parameter ``WP_RADIUS``, 0.08 m as in
  Sec. 4-4); param3 (pass radius) and param4 (yaw) are kept and returned but not used (the
  rig keeps its heading). Position x, y, z in the item's frame.
* ``MAV_CMD_NAV_TAKEOFF``: climb to altitude z at the horizontal position the rig has when
  the leg starts (x, y are not used).
* ``MAV_CMD_NAV_LAND``: descend to the ground (local Z = 0, the rig's virtual ground) at the
  item's position, or where the rig is when the leg starts if the position is "unset"
  (global frames: latitude and longitude both 0, or NaN; local frames: NaN).
* ``MAV_CMD_DO_CHANGE_SPEED``: param2 speed (m/s) of the following legs; -1 or NaN = no
  change, -2 = back to the rig's ``guidance.speed``; otherwise it must be in (0, 100]. The
  speed in force for a leg is that of the last DO_CHANGE_SPEED before it in sequence order,
  whichever item the mission starts from. Its frame is not used.
* ``MAV_CMD_NAV_LOITER_TIME``: fly to the item's position (or stay where the rig is when the
  position is unset, as for NAV_LAND) and hold there param1 seconds (>= 0); param2-4 (heading
  required, radius, exit) are kept but not used (a multicopter loiters on the spot).
* ``MAV_CMD_NAV_DELAY``: hold where the rig is for param1 seconds (>= 0; -1, the
  time-of-day form, is refused); its frame and position are not used.
* ``MAV_CMD_NAV_RETURN_TO_LAUNCH``: the mission ends here and the rig returns to home and
  lands (its AUTO.RTL mode, as PX4 does); items after it are not flown. Frame not used.
* ``MAV_CMD_HILMS_SYSID`` (the hilms dialect): the identification flight, flown when the mission
  reaches it (param1 must be 1; the other params and the frame are not used). Its programme
  ends disarmed, so it ends the mission: it must be the last item (an item after it is
  refused at upload, ``MAV_MISSION_INVALID``, naming both items).
* ``MAV_CMD_DO_JUMP``: param1 the item to jump to, param2 how many times (0..100). The plan
  unrolls the jumps (at most :data:`MAX_LEGS` legs), so a resumed or restarted mission
  repeats them from the start.

Frames of the position commands (anything else: ``MAV_MISSION_UNSUPPORTED_FRAME``):
``MAV_FRAME_GLOBAL(_INT)`` (altitude above the ellipsoid-as-AMSL, see
:mod:`protocol.geodesy`), ``MAV_FRAME_GLOBAL_RELATIVE_ALT(_INT)`` (altitude above home),
``MAV_FRAME_LOCAL_NED`` and ``MAV_FRAME_LOCAL_ENU`` (metres about home, the local origin).
Positions become the rig's world ENU about ``home`` with :mod:`protocol.geodesy`.

Validation answers with the MAV_MISSION_RESULT the mission protocol defines:
INVALID_PARAM1 / INVALID_PARAM2 for a bad hold / radius / speed, INVALID_PARAM5_X /
INVALID_PARAM6_Y for a latitude / longitude outside its range or a non-finite position,
INVALID_PARAM7 for a non-finite altitude or a take-off below the ground.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from protocol.dialect import mavlink as M
from protocol.geodesy import Home, global_to_local_enu, local_enu_to_global, surface_offset
from protocol.frames import enu_to_ned, ned_to_enu

GLOBAL_FRAMES = frozenset({M.MAV_FRAME_GLOBAL, M.MAV_FRAME_GLOBAL_INT})
RELATIVE_FRAMES = frozenset({M.MAV_FRAME_GLOBAL_RELATIVE_ALT, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT})
LOCAL_FRAMES = frozenset({M.MAV_FRAME_LOCAL_NED, M.MAV_FRAME_LOCAL_ENU})
POSITION_FRAMES = GLOBAL_FRAMES | RELATIVE_FRAMES | LOCAL_FRAMES
NAV_COMMANDS = frozenset({M.MAV_CMD_NAV_WAYPOINT, M.MAV_CMD_NAV_TAKEOFF, M.MAV_CMD_NAV_LAND,
                          M.MAV_CMD_NAV_LOITER_TIME, M.MAV_CMD_NAV_DELAY, M.MAV_CMD_NAV_RETURN_TO_LAUNCH})
SUPPORTED_COMMANDS = NAV_COMMANDS | {M.MAV_CMD_DO_CHANGE_SPEED, M.MAV_CMD_DO_JUMP, M.MAV_CMD_HILMS_SYSID}
#: items that need no position (their frame is not used)
POSITIONLESS_COMMANDS = frozenset({M.MAV_CMD_DO_CHANGE_SPEED, M.MAV_CMD_DO_JUMP, M.MAV_CMD_NAV_DELAY,
                                   M.MAV_CMD_NAV_RETURN_TO_LAUNCH, M.MAV_CMD_HILMS_SYSID})
MAX_LEGS = 10_000  # legs of a plan once DO_JUMP repeats are unrolled
MAX_JUMP_REPEAT = 100
HOLD_XY, HOLD_XYZ = 1.0, 2.0  # free_xy codes: keep X/Y (take-off, land here), keep X/Y/Z (delay, loiter here)
GLOBAL_SCALE = 1e7  # MISSION_ITEM_INT: degrees * 1e7
LOCAL_SCALE = 1e4  # MISSION_ITEM_INT: metres * 1e4 (PX4's reading of the field)
MAX_SPEED_M_S = 100.0  # guidance.speed's schema bound
SPEED_NO_CHANGE = -1.0
SPEED_DEFAULT = -2.0
INT32_MAX = 2**31 - 1


@dataclass(frozen=True)
class MissionItem:
    """One mission item; ``x``/``y`` in degrees (global frames), metres (local) or raw."""

    seq: int
    frame: int
    command: int
    current: int = 0
    autocontinue: int = 1
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    mission_type: int = M.MAV_MISSION_TYPE_MISSION

    def with_seq(self, seq: int) -> "MissionItem":
        return replace(self, seq=seq)


def _xy_scale(frame: int) -> float:
    if frame in GLOBAL_FRAMES or frame in RELATIVE_FRAMES:
        return GLOBAL_SCALE
    if frame in LOCAL_FRAMES:
        return LOCAL_SCALE
    return 1.0


def item_from_message(msg) -> MissionItem:
    """The item a MISSION_ITEM or MISSION_ITEM_INT carries (x/y unscaled to natural units)."""
    if msg.get_type() == "MISSION_ITEM_INT":
        scale = _xy_scale(msg.frame)
        x, y = msg.x / scale, msg.y / scale
    else:
        x, y = float(msg.x), float(msg.y)
    return MissionItem(seq=msg.seq, frame=msg.frame, command=msg.command, current=msg.current,
                       autocontinue=msg.autocontinue, param1=float(msg.param1), param2=float(msg.param2),
                       param3=float(msg.param3), param4=float(msg.param4), x=x, y=y, z=float(msg.z),
                       mission_type=getattr(msg, "mission_type", M.MAV_MISSION_TYPE_MISSION))


def _to_int(value: float, scale: float) -> int:
    if not math.isfinite(value):
        return 0
    return max(-INT32_MAX - 1, min(INT32_MAX, int(round(value * scale))))


def item_to_int_message(item: MissionItem, target_system: int = 0, target_component: int = 0):
    """MISSION_ITEM_INT of ``item`` (x/y scaled by 1e7 global, 1e4 local, 1 otherwise)."""
    scale = _xy_scale(item.frame)
    return M.MAVLink_mission_item_int_message(
        target_system=target_system, target_component=target_component, seq=item.seq, frame=item.frame,
        command=item.command, current=item.current, autocontinue=item.autocontinue, param1=item.param1,
        param2=item.param2, param3=item.param3, param4=item.param4, x=_to_int(item.x, scale),
        y=_to_int(item.y, scale), z=item.z, mission_type=item.mission_type)


def item_to_float_message(item: MissionItem, target_system: int = 0, target_component: int = 0):
    """MISSION_ITEM (the deprecated float form) of ``item``."""
    return M.MAVLink_mission_item_message(
        target_system=target_system, target_component=target_component, seq=item.seq, frame=item.frame,
        command=item.command, current=item.current, autocontinue=item.autocontinue, param1=item.param1,
        param2=item.param2, param3=item.param3, param4=item.param4, x=item.x, y=item.y, z=item.z,
        mission_type=item.mission_type)


# --- validation ------------------------------------------------------------------------------
def _land_here(item: MissionItem) -> bool:
    if item.frame in LOCAL_FRAMES:
        return math.isnan(item.x) or math.isnan(item.y)
    return (math.isnan(item.x) or math.isnan(item.y)) or (item.x == 0.0 and item.y == 0.0)


def validate_item(item: MissionItem, home: Home | None = None) -> tuple[int, str]:
    """(MAV_MISSION_RESULT, reason): ``MAV_MISSION_ACCEPTED`` and "" when the rig can fly it.

    Without ``home`` a take-off in MAV_FRAME_GLOBAL(_INT) cannot be checked against the ground."""
    cmd = item.command
    if cmd not in SUPPORTED_COMMANDS:
        name = M.enums["MAV_CMD"][cmd].name if cmd in M.enums["MAV_CMD"] else str(cmd)
        return M.MAV_MISSION_UNSUPPORTED, f"item {item.seq}: command {name} is not supported"
    if cmd == M.MAV_CMD_DO_CHANGE_SPEED:
        v = item.param2
        if math.isnan(v) or v in (SPEED_NO_CHANGE, SPEED_DEFAULT) or 0.0 < v <= MAX_SPEED_M_S:
            return M.MAV_MISSION_ACCEPTED, ""
        return M.MAV_MISSION_INVALID_PARAM2, f"item {item.seq}: speed {v:g} m/s must be in (0, {MAX_SPEED_M_S:g}], -1 or -2"
    if cmd == M.MAV_CMD_DO_JUMP:
        target, repeat = item.param1, item.param2
        if not (math.isfinite(target) and target >= 0 and target == int(target)):
            return M.MAV_MISSION_INVALID_PARAM1, f"item {item.seq}: jump target {target:g} must be an item number"
        if not (math.isfinite(repeat) and 0 <= repeat <= MAX_JUMP_REPEAT and repeat == int(repeat)):
            return M.MAV_MISSION_INVALID_PARAM2, (f"item {item.seq}: jump repeat {repeat:g} must be a whole number in "
                                                  f"0..{MAX_JUMP_REPEAT}")
        return M.MAV_MISSION_ACCEPTED, ""
    if cmd == M.MAV_CMD_HILMS_SYSID:
        if item.param1 != 1.0:
            return M.MAV_MISSION_INVALID_PARAM1, (f"item {item.seq}: MAV_CMD_HILMS_SYSID param1 {item.param1:g} "
                                                  "must be 1 (fly the identification flight)")
        return M.MAV_MISSION_ACCEPTED, ""
    if cmd in (M.MAV_CMD_NAV_DELAY, M.MAV_CMD_NAV_LOITER_TIME):
        if not (0.0 <= item.param1 < math.inf):
            return M.MAV_MISSION_INVALID_PARAM1, f"item {item.seq}: time {item.param1:g} s must be >= 0"
    if cmd in (M.MAV_CMD_NAV_DELAY, M.MAV_CMD_NAV_RETURN_TO_LAUNCH):
        return M.MAV_MISSION_ACCEPTED, ""
    if item.frame not in POSITION_FRAMES:
        name = M.enums["MAV_FRAME"][item.frame].name if item.frame in M.enums["MAV_FRAME"] else str(item.frame)
        return M.MAV_MISSION_UNSUPPORTED_FRAME, f"item {item.seq}: frame {name} is not supported"
    if cmd == M.MAV_CMD_NAV_WAYPOINT:
        if not (math.isnan(item.param1) or 0.0 <= item.param1 < math.inf):
            return M.MAV_MISSION_INVALID_PARAM1, f"item {item.seq}: hold time {item.param1:g} s must be >= 0"
        if not (math.isnan(item.param2) or 0.0 <= item.param2 < math.inf):
            return M.MAV_MISSION_INVALID_PARAM2, f"item {item.seq}: acceptance radius {item.param2:g} m must be >= 0"
    if not math.isfinite(item.z):
        return M.MAV_MISSION_INVALID_PARAM7, f"item {item.seq}: altitude {item.z:g} is not a finite number"
    if cmd == M.MAV_CMD_NAV_TAKEOFF:
        if _takeoff_up(item, home) < 0.0:
            return M.MAV_MISSION_INVALID_PARAM7, f"item {item.seq}: take-off altitude below the ground"
        return M.MAV_MISSION_ACCEPTED, ""
    if cmd in (M.MAV_CMD_NAV_LAND, M.MAV_CMD_NAV_LOITER_TIME) and _land_here(item):
        return M.MAV_MISSION_ACCEPTED, ""
    if item.frame in LOCAL_FRAMES:
        if not math.isfinite(item.x):
            return M.MAV_MISSION_INVALID_PARAM5_X, f"item {item.seq}: x {item.x:g} m is not a finite number"
        if not math.isfinite(item.y):
            return M.MAV_MISSION_INVALID_PARAM6_Y, f"item {item.seq}: y {item.y:g} m is not a finite number"
    else:
        if not -90.0 <= item.x <= 90.0:
            return M.MAV_MISSION_INVALID_PARAM5_X, f"item {item.seq}: latitude {item.x:g} deg outside [-90, 90]"
        if not -180.0 <= item.y <= 180.0:
            return M.MAV_MISSION_INVALID_PARAM6_Y, f"item {item.seq}: longitude {item.y:g} deg outside [-180, 180]"
    return M.MAV_MISSION_ACCEPTED, ""


# --- items -> the rig's mission ---------------------------------------------------------------
@dataclass(frozen=True)
class MissionPlan:
    """What the rig flies: one entry per navigation item, world ENU about home (SI)."""

    waypoints: np.ndarray  # (N, 3) m
    radii: np.ndarray  # (N,) m, 0 = the rig's switching radius
    holds: np.ndarray  # (N,) s
    speeds: np.ndarray  # (N,) m/s of the leg ending at each waypoint, 0 = the rig's speed
    free_xy: np.ndarray  # (N,) 1 = X/Y where the rig is when the leg starts
    seqs: tuple  # mission item seq of each waypoint
    count: int  # items in the mission (including non-navigation items and a home item 0)
    first_seq: int  # first item that is flown (1 with the ArduPilot item-0 convention)
    lands: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (N,) 1 = a landing leg (NAV_LAND)
    #: (N,) horizontal distance from home of each waypoint (m; along the ellipsoid for a global
    #: item, NaN where the leg keeps the X/Y the rig has): what the fence check measures
    horizontal_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    return_seq: int = -1  # a NAV_RETURN_TO_LAUNCH item ends the legs: the rig returns (AUTO.RTL); -1 none
    sysid_seq: int = -1  # a MAV_CMD_HILMS_SYSID item ends the legs: the identification flight; -1 none

    @property
    def size(self) -> int:
        return len(self.seqs)

    def nav_index(self, seq: int) -> int | None:
        """Waypoint index of the first navigation item at or after ``seq`` (None: there is none)."""
        for i, s in enumerate(self.seqs):
            if s >= seq:
                return i
        return None


def _takeoff_up(item: MissionItem, home: Home | None) -> float:
    if item.frame in GLOBAL_FRAMES:
        return item.z - (home.alt_m if home is not None else -math.inf)
    if item.frame == M.MAV_FRAME_LOCAL_NED:
        return -item.z
    return item.z  # relative altitude, LOCAL_ENU up


def item_height(item: MissionItem, home: Home) -> float:
    """The item's altitude as its frame means it, as a height above home (m): GLOBAL above mean
    sea level (home's altitude subtracted), GLOBAL_RELATIVE_ALT above home, LOCAL_NED -z,
    LOCAL_ENU z. The rig's world is flat about home (its virtual ground is level), so this is
    the height it flies, wherever the item lies on the Earth."""
    if item.frame in GLOBAL_FRAMES:
        return float(item.z) - home.alt_m
    if item.frame == M.MAV_FRAME_LOCAL_NED:
        return -float(item.z)
    return float(item.z)


def item_position_enu(item: MissionItem, home: Home) -> np.ndarray:
    """World ENU (m) about ``home`` of a position item (x, y taken as given): east and north on
    the tangent plane at home, up the item's height by its frame (:func:`item_height`), not the
    tangent plane's, which would read the Earth's curvature as depth (196 m at 50 km)."""
    up = item_height(item, home)
    if item.frame in GLOBAL_FRAMES or item.frame in RELATIVE_FRAMES:
        enu = global_to_local_enu(home, item.x, item.y, home.alt_m + up)
        return np.array([enu[0], enu[1], up], dtype=float)
    if item.frame == M.MAV_FRAME_LOCAL_NED:
        return np.array([item.y, item.x, up], dtype=float)
    return np.array([item.x, item.y, up], dtype=float)


def item_horizontal_m(item: MissionItem, home: Home, pos_enu) -> float:
    """Horizontal distance (m) of a position item from home: along the ellipsoid for a global
    item (:func:`protocol.geodesy.surface_offset`), on the local plane for a local one."""
    if item.frame in GLOBAL_FRAMES or item.frame in RELATIVE_FRAMES:
        return surface_offset(home, item.x, item.y)[0]
    return math.hypot(float(pos_enu[0]), float(pos_enu[1]))


def mission_plan(items, home: Home, item0_home: bool = False) -> MissionPlan:
    """The rig's mission of validated ``items`` (in seq order 0..N-1); raises ValueError
    naming the item when one cannot be flown."""
    items = list(items)
    for i, item in enumerate(items):
        if item.seq != i:
            raise ValueError(f"item {i} has seq {item.seq}: items must be numbered 0..{len(items) - 1}")
        result, reason = validate_item(item, home)
        if result != M.MAV_MISSION_ACCEPTED:
            raise ValueError(reason)
    first = 1 if item0_home else 0
    wps, radii, holds, speeds, free, seqs, lands, horiz = [], [], [], [], [], [], [], []
    speed = 0.0
    return_seq = sysid_seq = -1
    jumps_left: dict[int, int] = {}
    pc = first
    while pc < len(items):
        item = items[pc]
        pc += 1
        if item.command == M.MAV_CMD_DO_CHANGE_SPEED:
            v = item.param2
            if v == SPEED_DEFAULT:
                speed = 0.0
            elif not (math.isnan(v) or v == SPEED_NO_CHANGE):
                speed = float(v)
            continue
        if item.command == M.MAV_CMD_DO_JUMP:
            target = int(item.param1)
            if not first <= target < len(items) or target == item.seq:
                raise ValueError(f"item {item.seq}: jump target {target} not in {first}..{len(items) - 1} "
                                 f"(and not itself)")
            left = jumps_left.setdefault(item.seq, int(item.param2))
            if left > 0:
                jumps_left[item.seq] = left - 1
                pc = target
            continue
        if item.command == M.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            return_seq = item.seq
            break
        if item.command == M.MAV_CMD_HILMS_SYSID:
            if pc < len(items):
                raise ValueError(f"item {items[pc].seq}: nothing may follow item {item.seq} MAV_CMD_HILMS_SYSID (the "
                                 "identification flight ends disarmed): end the mission there")
            sysid_seq = item.seq
            break
        radius, hold, free_xy, land = 0.0, 0.0, 0.0, 0.0
        from_item = item.command in (M.MAV_CMD_NAV_WAYPOINT, M.MAV_CMD_NAV_LOITER_TIME, M.MAV_CMD_NAV_LAND)
        if item.command == M.MAV_CMD_NAV_WAYPOINT:
            pos = item_position_enu(item, home)
            hold = 0.0 if math.isnan(item.param1) else item.param1
            radius = 0.0 if math.isnan(item.param2) else item.param2
        elif item.command == M.MAV_CMD_NAV_TAKEOFF:
            pos = np.array([0.0, 0.0, _takeoff_up(item, home)])
            free_xy = HOLD_XY
            if pos[2] < 0.0:
                raise ValueError(f"item {item.seq}: take-off altitude {item.z:g} m is below the ground")
        elif item.command == M.MAV_CMD_NAV_DELAY:
            pos, free_xy, hold = np.zeros(3), HOLD_XYZ, item.param1
        elif item.command == M.MAV_CMD_NAV_LOITER_TIME:
            hold = item.param1
            if _land_here(item):
                pos, free_xy = np.zeros(3), HOLD_XYZ
            else:
                pos = item_position_enu(item, home)
        else:  # NAV_LAND
            if _land_here(item):
                pos, free_xy = np.zeros(3), HOLD_XY
            else:
                pos = item_position_enu(item, home)
            pos[2] = 0.0
            land = 1.0
        if not np.all(np.isfinite(pos)):
            raise ValueError(f"item {item.seq}: position is not finite in the local frame")
        horiz.append(item_horizontal_m(item, home, pos) if from_item and not free_xy else math.nan)
        wps.append(pos)
        radii.append(radius)
        holds.append(hold)
        speeds.append(speed)
        free.append(free_xy)
        seqs.append(item.seq)
        lands.append(land)
        if len(seqs) > MAX_LEGS:
            raise ValueError(f"more than {MAX_LEGS} legs once the DO_JUMP repeats are unrolled")
    n = len(seqs)
    return MissionPlan(waypoints=np.asarray(wps, dtype=float).reshape(n, 3), radii=np.asarray(radii, dtype=float),
                       holds=np.asarray(holds, dtype=float), speeds=np.asarray(speeds, dtype=float),
                       free_xy=np.asarray(free, dtype=float), seqs=tuple(seqs), count=len(items), first_seq=first,
                       lands=np.asarray(lands, dtype=float), return_seq=return_seq, sysid_seq=sysid_seq,
                       horizontal_m=np.asarray(horiz, dtype=float))


# --- the rig's mission -> items (ground tools, tests) ----------------------------------------------
def _f32(value) -> float:
    """The value a float32 field carries."""
    return float(np.float32(value))


def waypoint_items(waypoints_enu, home: Home, frame: int = M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                   hold_s: float = 0.0, radius_m: float = 0.0, speed_m_s: float | None = None,
                   first_seq: int = 0) -> list[MissionItem]:
    """NAV_WAYPOINT items for world-ENU waypoints (m) about ``home`` in ``frame``; with
    ``speed_m_s`` a DO_CHANGE_SPEED item comes first. The first item has ``current = 1``
    (MAVSDK insists on exactly one). Every number is rounded to what
    MISSION_ITEM_INT carries (1e-7 deg global, 1e-4 m local, float32 params and z), so a
    downloaded copy compares equal."""
    if frame not in POSITION_FRAMES:
        raise ValueError(f"frame {frame}: use one of {sorted(POSITION_FRAMES)}")
    wp = np.asarray(waypoints_enu, dtype=float).reshape(-1, 3)
    items: list[MissionItem] = []
    seq = first_seq
    if speed_m_s is not None:
        items.append(MissionItem(seq=seq, frame=M.MAV_FRAME_MISSION, command=M.MAV_CMD_DO_CHANGE_SPEED,
                                 param1=1.0, param2=_f32(speed_m_s), param3=-1.0))
        seq += 1
    for p in wp:
        if frame in LOCAL_FRAMES:
            x, y, z = p if frame == M.MAV_FRAME_LOCAL_ENU else enu_to_ned(p)
            x, y = round(float(x) * LOCAL_SCALE) / LOCAL_SCALE, round(float(y) * LOCAL_SCALE) / LOCAL_SCALE
        else:
            lat, lon, _alt = local_enu_to_global(home, p)
            x, y = round(lat * GLOBAL_SCALE) / GLOBAL_SCALE, round(lon * GLOBAL_SCALE) / GLOBAL_SCALE
            z = p[2] if frame in RELATIVE_FRAMES else p[2] + home.alt_m  # the frame's altitude (item_height)
        items.append(MissionItem(seq=seq, frame=frame, command=M.MAV_CMD_NAV_WAYPOINT, param1=_f32(hold_s),
                                 param2=_f32(radius_m), x=float(x), y=float(y), z=_f32(z)))
        seq += 1
    if items:
        items[0] = replace(items[0], current=1)
    return items
