"""The controller plug-in interface: what a user subclasses (docs/how-to/your-controller.md).

Modelled on RotorPy's controller template (an object with ``update(t, state, flat_output)``
returning motor speeds, thrust plus attitude or body rates), on this rig's terms: the
controller sees what the onboard computer sees (:class:`~rig_emulator.controllers.observation.Observation`)
and declares what it replaces and what it commands.

Two kinds, one interface:

* :class:`Controller` - plain Python. ``update(t, obs)`` returns four numbers (or a
  :class:`Command`). The plant stays compiled; the loop calls back into Python at the
  controller's rate.
* :class:`CompiledController` - its ``kernel`` is a ``numba.njit`` function
  ``kernel(t, obs, params, state, out) -> int`` on float64 arrays (layout:
  :mod:`rig_emulator.control.plugin_layout`); it runs inside the compiled loop. The same
  kernel also runs as plain Python (``python=True`` when loading), e.g. to debug it.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from rig_emulator.control import plugin_layout as PL

#: what a controller replaces -> loop mode
REPLACES = {"both": PL.P_BOTH, "attitude": PL.P_ATTITUDE, "position": PL.P_POSITION}
#: what it commands -> kind, with the unit of the four numbers
COMMANDS = {
    "motor_voltages": (PL.K_VOLTAGES, "motor voltages 1-4 (V)"),
    "motor_thrusts": (PL.K_THRUSTS, "motor thrusts 1-4 (N)"),
    "torques": (PL.K_TORQUES, "u1 (N) and body torques u2, u3, u4 (N m, FRD)"),
    "attitude": (PL.K_ATTITUDE, "u1 (N) and desired phi, theta, psi (rad)"),
}
#: which commands go with which replacement
ALLOWED = {
    "both": ("motor_voltages", "motor_thrusts", "torques"),
    "attitude": ("motor_voltages", "motor_thrusts", "torques"),
    "position": ("attitude",),
}


class PluginError(RuntimeError):
    """A controller plug-in could not be loaded, or failed while flying.

    ``plugin`` names it (``module:Name``), ``time_s`` is the simulated time of the failure
    (None when loading), ``problem`` says what went wrong.
    """

    def __init__(self, plugin: str, problem: str, time_s: float | None = None):
        super().__init__(plugin, problem, time_s)
        self.plugin = plugin
        self.problem = problem
        self.time_s = time_s

    def __str__(self) -> str:
        when = "" if self.time_s is None else f" at t = {self.time_s:.3f} s"
        return f"controller {self.plugin}{when}: {self.problem}"


#: What ``update`` may return instead of four bare numbers: the command and, optionally, the
#: attitude it aims at (rad, rad/s; shown in logs and telemetry, used by the loss-of-control
#: supervisor).
Command = namedtuple("Command", "values attitude_des attitude_rate_des", defaults=(None, None))


class ControllerParams:
    """A controller's own parameters: named floats or fixed-length float vectors in one flat
    float64 array (``array``, what a compiled kernel receives as ``params``).

    ``params.kp`` is a plain attribute: a float, or a read-only view of the array for a
    vector, resolved when a value changes, not at every read (a read costs what an attribute
    costs; a plain-Python controller reads them at every step). Every change goes through
    :meth:`set` (the config, ``--set``, :meth:`LiveRig.set_params`, PARAM_SET), which
    refreshes them; code that writes :attr:`array` in place calls :meth:`refresh` afterwards.
    A parameter whose name is one of this class's own attributes (``set``, ``array``, ...)
    is read with ``params.get(name)``.
    """

    def __init__(self, defaults: dict, values: dict | None = None, owner: str = "controller",
                 info: dict | None = None):
        self._slices: dict[str, slice] = {}
        self.info = info or {}  # name -> {"min", "max", "unit", "doc"} (Controller.param_info)
        flat: list[float] = []
        for name, default in defaults.items():
            if not name.isidentifier():
                raise PluginError(owner, f"parameter name {name!r} is not an identifier")
            v = np.atleast_1d(np.asarray(default, dtype=np.float64)).ravel()
            self._slices[name] = slice(len(flat), len(flat) + v.size) if np.ndim(default) else slice(len(flat), len(flat) + 1)
            flat.extend(float(a) for a in v)
        self._scalar = {n: np.ndim(d) == 0 for n, d in defaults.items()}
        self.array = np.ascontiguousarray(flat if flat else [0.0], dtype=np.float64)
        self.owner = owner
        # the names read as attributes: not those of this class's own methods and fields
        self._plain = tuple(n for n in self._slices if not hasattr(type(self), n) and n not in self.__dict__)
        self._bind()
        for name, value in (values or {}).items():
            self.set(name, value)

    def _bind(self) -> None:
        for name in self._plain:
            if not self._scalar[name]:
                view = self.array[self._slices[name]]
                view.flags.writeable = False
                self.__dict__[name] = view  # a view: follows the array whatever writes it
        self.refresh()

    def __getstate__(self):  # the views are rebuilt on the unpickled array
        state = dict(self.__dict__)
        for name in self._plain:
            state.pop(name, None)
        return state

    def __setstate__(self, state) -> None:
        self.__dict__.update(state)
        self._bind()

    def refresh(self) -> None:
        """Resolve the scalar attributes from :attr:`array` again (after writing it in place)."""
        a = self.array
        d = self.__dict__
        for name in self._plain:
            if self._scalar[name]:
                d[name] = float(a[self._slices[name].start])

    def names(self):
        return tuple(self._slices)

    def index(self, name: str) -> slice:
        """Where parameter ``name`` lives in :attr:`array` (for compiled kernels)."""
        return self._slices[name]

    def get(self, name: str):
        """The current value of ``name``: a float, or a read-only view for a vector."""
        sl = self._slices[name]
        if self._scalar[name]:
            return float(self.array[sl.start])
        view = self.array[sl]
        view.flags.writeable = False
        return view

    def set(self, name: str, value) -> None:
        """Set one parameter (a number, or as many numbers as its default has); validated. The
        errors name the parameter as the config does (``controller.params.NAME``) and its range."""
        key = f"controller.params.{name}"
        if name not in self._slices:
            import difflib

            hint = difflib.get_close_matches(str(name), self._slices, n=1)
            did = f" (did you mean 'controller.params.{hint[0]}'?)" if hint else ""
            raise PluginError(self.owner, f"unknown parameter {key!r}{did}; its parameters: "
                                          f"{', '.join(self._slices) or 'none'}")
        sl = self._slices[name]
        n = sl.stop - sl.start
        lo, hi = self.limits(name)
        unit = self.info.get(name, {}).get("unit", "")
        bounded = not (math.isinf(lo) and math.isinf(hi))
        rng = f"in [{lo:g}, {hi:g}]" + (f" {unit}" if unit else "")
        if self._scalar[name]:
            what = f"a number {rng}" if bounded else "a finite number"
        else:
            what = f"{n} numbers, each {rng}" if bounded else f"{n} finite numbers"
        try:
            v = np.atleast_1d(np.asarray(value, dtype=np.float64)).ravel()
        except (TypeError, ValueError):
            raise PluginError(self.owner, f"{key} = {value!r}: must be {what}") from None
        if v.size != n:
            raise PluginError(self.owner, f"{key} = {value!r}: must be {what} (got {v.size} value(s))")
        if not np.all(np.isfinite(v)):
            raise PluginError(self.owner, f"{key} = {value!r}: must be finite" + (f", {rng}" if bounded else ""))
        if np.any(v < lo) or np.any(v > hi):
            raise PluginError(self.owner, f"{key} = {value!r}: must be {rng}")
        self.array[sl] = v
        if self._scalar[name] and name in self._plain:
            self.__dict__[name] = float(self.array[sl.start])

    def limits(self, name: str) -> tuple[float, float]:
        """(min, max) of parameter ``name`` from the controller's ``param_info`` (+-inf when not given)."""
        info = self.info.get(name, {})
        return float(info.get("min", -math.inf)), float(info.get("max", math.inf))

    def __getattr__(self, name):  # only reached for names that are not plain attributes
        slices = self.__dict__.get("_slices", {})
        if name in slices:
            return self.get(name)
        raise AttributeError(name)

    def as_dict(self) -> dict:
        return {n: (float(self.array[s.start]) if self._scalar[n] else self.array[s].tolist())
                for n, s in self._slices.items()}


class Controller:
    """Base class of a controller plug-in. Subclass it and override :meth:`update`.

    Class attributes (the declaration, checked when the rig loads it):

    * ``replaces``: ``"both"`` (position and attitude loops), ``"attitude"`` (the rig's
      position loop of the configured strategy feeds it ``obs.attitude_target`` and
      ``obs.thrust_target``) or ``"position"`` (it commands an attitude, the rig's attitude
      loop of the configured strategy does the rest);
    * ``commands``: ``"motor_voltages"``, ``"motor_thrusts"``, ``"torques"`` (u1 and body
      torques; the rig's allocation does the rest) or ``"attitude"`` (u1 and the desired
      Euler angles; only with ``replaces = "position"``);
    * ``rate_hz``: how often ``update`` runs (None: the rig's ``sim.control_rate_hz``); a
      whole divisor of the physics rate. A position-only controller may run slower than the
      rig's attitude loop (a whole multiple of its period); the others set the period of
      the whole onboard loop (guidance, Eq. 1, supervisor);
    * ``raw_sensors``: True to receive the raw IMU and load-cell samples (``obs.imu_raw``,
      ``obs.cell_raw``);
    * ``params``: the defaults of its own parameters (name -> number or list of numbers);
      set from the config (``[controller.params]``) or, served, as MAVLink parameters
      ``<param_prefix><NAME><i>``;
    * ``param_prefix``: that prefix (upper case, ends with ``_``; empty: not served);
      a vector parameter is served one element a name, numbered from 1 (``MYC_KD1``..``MYC_KD3``);
    * ``param_info`` (optional): per parameter ``{"min": .., "max": .., "unit": "..", "doc": ".."}``:
      every change (config, :meth:`LiveRig.set_params`, PARAM_SET) outside [min, max] is
      refused with a message; unit and doc go to the ground station's parameter metadata.

    :meth:`reset` runs on arming, before the first :meth:`update`. Keep state on ``self``.
    """

    replaces = "both"
    commands = "torques"
    rate_hz: float | None = None
    raw_sensors = False
    params: dict = {}
    param_prefix = ""
    param_info: dict = {}

    def __init__(self, **params):
        self.params = ControllerParams(type(self).params, params, owner=type(self).__qualname__,
                                       info=type(self).param_info)

    def reset(self) -> None:
        """Forget everything learnt in a previous flight (called on arming)."""

    def update(self, t: float, obs):
        """Return the command for time ``t``: four numbers (see ``commands``) or a :class:`Command`."""
        raise NotImplementedError


class CompiledController(Controller):
    """A controller whose law is a ``numba.njit`` kernel run inside the compiled step loop.

    ``kernel(t, obs, params, state, out) -> int``: ``obs`` (read it with the ``O_*``
    constants of :mod:`rig_emulator.control.plugin_layout`), ``params`` (this controller's
    ``params.array``), ``state`` (``state_size`` floats of its own, zeroed on arming, when
    ``obs[O_RESET]`` is 1), ``out`` (write the command at ``C_CMD``, optionally the attitude
    aimed at at ``C_ATT_DES``/``C_ATT_RATE_DES``). Return 0, or a non-zero code of your own
    to report a failure (the rig stops the run or goes to its failsafe and shows the code).
    """

    kernel = None
    state_size = 0

    def __init__(self, **params):
        super().__init__(**params)
        self.state = np.zeros(max(1, int(self.state_size)))

    def update(self, t, obs):
        """The kernel run as plain Python (numba's ``py_func``, and so are the compiled helpers it
        calls), for the Python call path."""
        out = np.full(PL.OUT_SIZE, math.nan)
        rc = _as_python(type(self).kernel)(t, obs.array, self.params.array, self.state, out)
        if rc:
            raise RuntimeError(f"kernel returned error code {int(rc)}")
        return Command(out[PL.C_CMD:PL.C_CMD + 4], out[PL.C_ATT_DES:PL.C_ATT_DES + 3],
                       out[PL.C_ATT_RATE_DES:PL.C_ATT_RATE_DES + 3])

    def reset(self) -> None:
        self.state[:] = 0.0


_PYTHON: dict = {}  # numba dispatcher -> its plain-Python function calling plain-Python helpers


def _as_python(dispatcher):
    """``dispatcher.py_func`` with every numba function it refers to (its globals and closure,
    recursively) replaced by that function's own plain-Python version."""
    fn = _PYTHON.get(dispatcher)
    if fn is not None:
        return fn
    import types

    from numba.core.registry import CPUDispatcher

    py = dispatcher.py_func
    glb = dict(py.__globals__)
    fn = types.FunctionType(py.__code__, glb, py.__name__, py.__defaults__, py.__closure__)
    _PYTHON[dispatcher] = fn  # before recursing: a kernel may call itself
    for name in py.__code__.co_names:
        value = glb.get(name)
        if isinstance(value, CPUDispatcher):
            glb[name] = _as_python(value)
    return fn
