"""Loading a controller plug-in by name and binding it to a rig's step loop.

:func:`load_controller` turns ``"my_pkg.my_module:MyController"`` (or a class, or an
instance) into a :class:`~rig_emulator.controllers.base.Controller`; :func:`bind` checks
its declaration against the rig's rates and builds what the compiled loop takes: a
:class:`~rig_emulator.control.plugin_step.PluginParams` and a function pointer, a
``numba.cfunc`` for a :class:`CompiledController`, a C callback into Python otherwise.
"""

from __future__ import annotations

import ctypes
import importlib
import math
import os
import traceback

import numba
import numpy as np
from numba import carray
from numba.core.types.function_type import WrapperAddressProtocol

from rig_emulator.control import plugin_layout as PL
from rig_emulator.control.plugin_step import PLUGIN_SIG, PluginParams
from rig_emulator.controllers.base import ALLOWED, COMMANDS, REPLACES, Command, CompiledController, Controller, PluginError
from rig_emulator.controllers.observation import Observation


def plugin_name(obj) -> str:
    """``module:QualName`` of a controller (its class)."""
    cls = obj if isinstance(obj, type) else type(obj)
    return f"{cls.__module__}:{cls.__qualname__}"


def load_controller(spec, params: dict | None = None) -> Controller:
    """A controller from ``"package.module:Name"`` (imported; ``Name`` a class, called with no
    arguments, or an object), a class or an instance; ``params`` override its defaults.
    Raises :class:`PluginError` naming the plug-in and the problem."""
    if isinstance(spec, str):
        module_name, sep, attr = spec.partition(":")
        if not sep or not module_name or not attr:
            raise PluginError(spec, "must be written 'package.module:Name'")
        try:
            module = importlib.import_module(module_name)
        except Exception as exc:  # an import error of any kind is the plug-in's problem
            raise PluginError(spec, f"cannot import {module_name!r}: {type(exc).__name__}: {exc}") from None
        obj = module
        for part in attr.split("."):
            obj = getattr(obj, part, None)
            if obj is None:
                raise PluginError(spec, f"module {module_name!r} has no {attr!r}")
        name = spec
    else:
        obj = spec
        name = plugin_name(spec)
    if isinstance(obj, type):
        if not issubclass(obj, Controller):
            raise PluginError(name, "is not a subclass of rig_emulator.controllers.Controller")
        try:
            obj = obj()
        except PluginError:
            raise
        except Exception as exc:
            raise PluginError(name, f"constructor failed: {type(exc).__name__}: {exc}") from None
    if not isinstance(obj, Controller):
        raise PluginError(name, f"is a {type(obj).__name__}, not a rig_emulator.controllers.Controller")
    for key, value in (params or {}).items():
        try:
            obj.params.set(key, value)
        except PluginError as exc:
            raise PluginError(name, exc.problem) from None
    obj.plugin_name = name
    return obj


class BoundPlugin:
    """A controller bound to one rig: the loop's arguments and what it reports on failure."""

    def __init__(self, params: PluginParams, fn, controller: Controller | None = None, name: str = "",
                 ctrl_div: int | None = None):
        self.params = params
        self.fn = fn
        self.controller = controller
        self.name = name
        self.ctrl_div = ctrl_div  # the onboard loop's period the plug-in imposes (None: the config's)
        self.exc: BaseException | None = None  # what a Python plug-in raised
        self.exc_where = ""
        self.observation = None  # a Python plug-in's Observation (PythonCall)

    def failure(self, dt: float) -> PluginError | None:
        """The plug-in's failure recorded by the loop (None: none)."""
        st = self.params.status
        code = int(st[PL.S_CODE])
        if code == 0:
            return None
        t = int(st[PL.S_STEP]) * dt
        unit = COMMANDS[self.controller.commands][1] if self.controller is not None else ""
        if code == PL.ERR_NONFINITE:
            values = ", ".join(f"{v:g}" for v in self.params.out[PL.C_CMD:PL.C_CMD + 4])
            problem = f"returned a non-finite command [{values}] ({unit})"
        elif self.exc is not None:
            problem = f"{type(self.exc).__name__}: {self.exc}{self.exc_where}"
        else:
            problem = f"returned error code {int(st[PL.S_RETURN])}"
        return PluginError(self.name, problem, t)

    def refresh_rig(self, cp) -> None:
        """New rig constants (a parameter change of the running rig) into the observation, and the
        built-in strategy's gains (what it flies, or the loop a plug-in leaves to it)."""
        if self.fn is None:  # the lockstep binding: no controller
            return
        from rig_emulator.controllers.builtin.kernel import pack_params

        fill_rig_constants(self.params.obs, cp)
        if self.observation is not None:
            self.observation.refresh()
        pack_params(cp, out=self.params.laws)

    def clear(self) -> None:
        """Forget a failure (on arming again)."""
        self.params.status[:] = 0
        self.exc = None
        self.exc_where = ""


def no_plugin_binding() -> BoundPlugin:
    """The loop's arguments without a controller: the motor voltages are set from outside (lockstep)."""
    params = PluginParams(PL.P_EXTERNAL, 0, 1, False, True, np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(PL.OUT_SIZE),
                          np.zeros(PL.STATUS_SIZE, dtype=np.int64), np.zeros(1), np.zeros(1), np.zeros(PL.OUT_SIZE))
    # fn None: the loop's controller branch is pruned at compile time (not compiled at all)
    return BoundPlugin(params, None, name="external motor commands")


def bind_builtin(cp, ctrl_div: int, strategy: str, n_imu: int) -> BoundPlugin:
    """The built-in strategy (``control.strategy``) on the plug-in interface: its kernel
    (:mod:`rig_emulator.controllers.builtin.kernel`) replaces both loops and commands torques at
    the rig's control rate, as a plug-in declared so would."""
    from rig_emulator.controllers.builtin.kernel import STATE_SIZE, STRATEGY_POINTER

    laws, rig_state, rig_out = _rig_laws(cp)  # its params are the laws the rig's other loops use
    params = PluginParams(PL.P_BOTH, PL.K_TORQUES, ctrl_div, False, False, _observation(cp, n_imu), laws,
                          np.zeros(STATE_SIZE), np.full(PL.OUT_SIZE, np.nan), np.zeros(PL.STATUS_SIZE, dtype=np.int64),
                          laws, rig_state, rig_out)
    return BoundPlugin(params, STRATEGY_POINTER, name=f"built-in {strategy}")


def _observation(cp, n_imu: int) -> np.ndarray:
    """A controller's ``obs`` before its first update: the rig's constants, no true state, NaN elsewhere."""
    obs = np.full(PL.OBS_SIZE, np.nan)
    obs[PL.O_TRUE_VALID] = 0.0
    obs[PL.O_N_IMU] = n_imu
    fill_rig_constants(obs, cp)
    return obs


def _rig_laws(cp) -> tuple:
    """The built-in strategy's parameters, memory and output for the loop a plug-in does not replace
    (``PluginParams.laws``, ``rig_state``, ``rig_out``)."""
    from rig_emulator.controllers.builtin.kernel import STATE_SIZE, pack_params

    return pack_params(cp), np.zeros(STATE_SIZE), np.full(PL.OUT_SIZE, np.nan)


def _divisor(name: str, what: str, rate: float, base: float) -> int:
    n = base / rate
    div = int(round(n))
    if div < 1 or abs(n - div) > 1e-9 * n:
        raise PluginError(name, f"rate_hz = {rate:g}: {what} ({base:g} Hz) must be a whole multiple of it")
    return div


def bind(controller: Controller, physics_rate_hz: float, control_rate_hz: float, cp, n_imu: int,
         python: bool = False) -> BoundPlugin:
    """Check ``controller``'s declaration against the rig and build the loop's arguments.

    ``python``: run a :class:`CompiledController`'s kernel as plain Python (debugging)."""
    name = getattr(controller, "plugin_name", plugin_name(controller))
    replaces, commands = controller.replaces, controller.commands
    if replaces not in REPLACES:
        raise PluginError(name, f"replaces = {replaces!r}: must be one of {', '.join(REPLACES)}")
    if commands not in COMMANDS:
        raise PluginError(name, f"commands = {commands!r}: must be one of {', '.join(COMMANDS)}")
    if commands not in ALLOWED[replaces]:
        raise PluginError(name, f"commands = {commands!r} does not go with replaces = {replaces!r} "
                                f"(allowed: {', '.join(ALLOWED[replaces])})")
    ctrl_div = _divisor(name, "the physics rate", control_rate_hz, physics_rate_hz)
    rate = controller.rate_hz if controller.rate_hz is not None else control_rate_hz
    if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate > 0):
        raise PluginError(name, f"rate_hz = {rate!r}: must be a positive number of Hz")
    div = _divisor(name, "the physics rate", float(rate), physics_rate_hz)
    if replaces == "position":
        if div % ctrl_div:
            raise PluginError(name, f"rate_hz = {rate:g}: a position controller runs at the rig's control rate "
                                    f"({control_rate_hz:g} Hz) or a whole divisor of it")
        loop_div = None
    else:
        loop_div = div
    if n_imu > PL.IMU_RAW_MAX:
        raise PluginError(name, f"the rig has {n_imu} IMU modules; plug-ins see at most {PL.IMU_RAW_MAX}")
    obs = _observation(cp, n_imu)
    compiled = isinstance(controller, CompiledController) and not python
    state = np.zeros(max(1, int(getattr(controller, "state_size", 0) or 0)))
    params = PluginParams(REPLACES[replaces], COMMANDS[commands][0], div, bool(controller.raw_sensors), True, obs,
                          controller.params.array, state, np.full(PL.OUT_SIZE, np.nan),
                          np.zeros(PL.STATUS_SIZE, dtype=np.int64), *_rig_laws(cp))
    bound = BoundPlugin(params, None, controller, name, loop_div)
    bound.fn = _compiled_call(controller, name, params) if compiled else PythonCall(bound, n_imu)
    return bound


def fill_rig_constants(obs: np.ndarray, cp) -> None:
    """The rig's constants (O_MASS .. O_REF_OMEGA) from the controller's parameters."""
    for i, v in enumerate((cp.mass, cp.g, cp.ixx, cp.iyy, cp.izz, cp.arm_length, cp.km_over_kf, cp.kf, cp.k_v,
                           cp.v_max, cp.f_max, cp.max_tilt, cp.ref_omega)):
        obs[PL.O_RIG + i] = v


_CFUNCS: dict = {}  # (kernel, n_params, n_state) -> cfunc


def _compiled_call(controller: CompiledController, name: str, params: PluginParams):
    kernel = type(controller).kernel
    if not isinstance(kernel, numba.core.registry.CPUDispatcher):
        raise PluginError(name, "kernel must be a numba.njit function kernel(t, obs, params, state, out) -> int")
    key = (kernel, params.params.shape[0], params.state.shape[0])
    fn = _CFUNCS.get(key)
    if fn is None:
        n_par, n_state = key[1], key[2]

        def call(t, o, p, s, out):
            return kernel(t, carray(o, (PL.OBS_SIZE,), np.float64), carray(p, (n_par,), np.float64),
                          carray(s, (n_state,), np.float64), carray(out, (PL.OUT_SIZE,), np.float64))

        try:
            fn = numba.cfunc(PLUGIN_SIG)(call)
        except Exception as exc:
            first = str(exc).strip().splitlines()
            raise PluginError(name, f"kernel does not compile: {type(exc).__name__}: "
                                    f"{first[0] if first else ''} ...") from None
        _CFUNCS[key] = fn
    return fn


_CALLBACK = ctypes.CFUNCTYPE(ctypes.c_int64, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                             ctypes.c_void_p)


def _c_callback(fn):
    """``fn`` as a C function of the plug-in signature: (the object to keep alive, its address).

    cffi's callbacks enter Python faster than ctypes' (``python -m benchmarks --only plugins``;
    docs/explanation/controller-speed.md); cffi is used when installed, ctypes otherwise or with
    ``HILMS_PLUGIN_CALLBACK=ctypes``. Both call ``fn`` alike: a run gives the same results."""
    if _FFI is not None and os.environ.get("HILMS_PLUGIN_CALLBACK") != "ctypes":
        cb = _FFI.callback("int64_t(double, void *, void *, void *, void *)", fn)
        return cb, int(_FFI.cast("uintptr_t", cb))
    cb = _CALLBACK(fn)
    return cb, ctypes.cast(cb, ctypes.c_void_p).value


try:
    import cffi

    _FFI = cffi.FFI()
except ImportError:  # optional: ctypes does the same, a little slower
    _FFI = None


class PythonCall(WrapperAddressProtocol):
    """A Python controller as the loop's function pointer (a cffi or ctypes callback).

    The callback never lets an exception out (the C caller would print it and go on): it
    stores it on the binding and returns 1; the loop then disarms and the caller reports.
    """

    def __init__(self, bound: BoundPlugin, n_imu: int):
        controller = bound.controller
        obs_array = bound.params.obs
        out = bound.params.out
        obs = Observation(obs_array, n_imu)
        bound.observation = obs  # refreshed with the rig's constants (BoundPlugin.refresh_rig)
        update = controller.update
        reset = controller.reset
        unit = COMMANDS[controller.commands][1]
        # per call: no allocation, no numpy scalars; memoryviews read and write Python floats
        obs_mv = memoryview(obs_array)
        out_mv = memoryview(out)
        o_reset = PL.O_RESET
        c0, c1, c2, c3 = range(PL.C_CMD, PL.C_CMD + 4)
        a0, a1, a2 = range(PL.C_ATT_DES, PL.C_ATT_DES + 3)
        r0, r1, r2 = range(PL.C_ATT_RATE_DES, PL.C_ATT_RATE_DES + 3)
        command = Command

        def callback(t, _obs, _params, _state, _out):
            try:
                if obs_mv[o_reset] != 0.0:
                    reset()
                result = update(t, obs)
            except BaseException as exc:  # noqa: BLE001 - reported by the caller, KeyboardInterrupt re-raised there
                bound.exc = exc
                bound.exc_where = _where(exc)
                return 1
            if type(result) is tuple and len(result) == 4:  # the common answer, written without numpy
                try:
                    a, b, c, d = result
                    out_mv[c0] = a
                    out_mv[c1] = b
                    out_mv[c2] = c
                    out_mv[c3] = d
                    return 0
                except Exception:  # noqa: BLE001 - not numbers: _store says what is wrong
                    pass
            elif type(result) is command:
                try:
                    values, att, rate = result
                    out_mv[c0], out_mv[c1], out_mv[c2], out_mv[c3] = values
                    if att is not None:
                        out_mv[a0], out_mv[a1], out_mv[a2] = att
                    if rate is not None:
                        out_mv[r0], out_mv[r1], out_mv[r2] = rate
                    return 0
                except Exception:  # noqa: BLE001 - _store says what is wrong
                    pass
            try:
                _store(result, out, unit)
            except Exception as exc:  # noqa: BLE001 - what update returned is wrong: point at update, not here
                bound.exc = exc
                bound.exc_where = _returned_by(update)
                return 1
            return 0

        self._callback, self._address = _c_callback(callback)

    def __wrapper_address__(self):
        return self._address

    def signature(self):
        return PLUGIN_SIG


def _where(exc: BaseException) -> str:
    tb = traceback.extract_tb(exc.__traceback__)
    if not tb:
        return ""
    last = tb[-1]
    return f" ({last.filename}:{last.lineno} in {last.name})"


def _returned_by(update) -> str:
    """`` (returned by FILE:LINE, QUALNAME)`` of a controller's ``update`` method."""
    fn = getattr(update, "__func__", update)
    code = getattr(fn, "__code__", None)
    if code is None:
        return ""
    return f" (returned by {getattr(fn, '__qualname__', code.co_name)}, {code.co_filename}:{code.co_firstlineno})"


def _store(result, out: np.ndarray, unit: str) -> None:
    att = rate = None
    if isinstance(result, Command):
        result, att, rate = result
    try:
        n = len(result)
    except TypeError:
        raise ValueError(f"update() must return 4 numbers ({unit}) or a Command, got {type(result).__name__}") from None
    if n != 4:
        raise ValueError(f"update() must return 4 numbers ({unit}), got {n}")
    out[PL.C_CMD:PL.C_CMD + 4] = result
    if att is not None:
        out[PL.C_ATT_DES:PL.C_ATT_DES + 3] = att
    if rate is not None:
        out[PL.C_ATT_RATE_DES:PL.C_ATT_RATE_DES + 3] = rate
