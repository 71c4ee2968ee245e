"""jit(nrt=False): the step loop runs without numba's reference counting (rig_emulator/_jit.py)."""

import sys
from collections import namedtuple

import numba
import numpy as np
import pytest

from rig_emulator.guidance import waypoint_switching
from rig_emulator._jit import jit
from rig_emulator.config.loader import load_config
from rig_emulator.control import allocation, controller, fuzzy, pid, plugin_step, reference_filter, smc, supervisor
from rig_emulator.controllers.builtin import kernel
from rig_emulator.estimation import (attitude_pipeline, complementary, ensemble, imu_calibration, load_cell_filter,
                                     onboard_position)
from rig_emulator.guidance import runner, trajectories
from rig_emulator.physics import disturbances, ground, integrator, rigid_body, rotation
from rig_emulator.sensors import imu_module, sensor_step
from rig_emulator.simulation import loop, rng_bits
from rig_emulator.simulation.run import Simulation

Pair = namedtuple("Pair", "a b")


@jit(cache=False)
def _accumulate(a, out):
    out[0] += a[0]


def _loop_with_branches(p, out, n):
    # what the step loop does: arrays taken out of a namedtuple, or sliced, handed to a
    # function that is not inlined, in a loop with branches
    for k in range(n):
        if k % 2 == 0:
            _accumulate(p.a, out)
        else:
            _accumulate(p.b[1:3], out)


def test_nrt_false_compiles_without_reference_counting():
    counted = jit(cache=False)(_loop_with_branches)
    plain = jit(nrt=False, cache=False, python=True)(_loop_with_branches)
    p = Pair(np.arange(3.0), np.arange(3.0) + 10.0)
    for f in (counted, plain):
        out = np.zeros(1)
        f(p, out, 5)
        assert out[0] == 3 * 0.0 + 2 * 11.0
    assert "NRT_incref" in counted.inspect_llvm(counted.signatures[0])
    ir = plain.inspect_llvm(plain.signatures[0])
    assert "NRT_incref" not in ir and "NRT_decref" not in ir


def test_a_loop_only_function_called_from_python_runs_its_twin():
    # nrt=False: no CPython wrapper (cold compile); a call from Python compiles a twin
    f = jit(nrt=False, cache=False)(_loop_with_branches)
    out = np.zeros(1)
    f(Pair(np.arange(3.0), np.arange(3.0) + 10.0), out, 5)
    assert out[0] == 22.0
    assert f.signatures == [] and len(f._python_twin.signatures) == 1
    assert f.targetoptions["no_cpython_wrapper"] is True


def test_nrt_false_refuses_to_allocate():
    def allocates(n):
        return np.zeros(n)[0]

    with pytest.raises(numba.core.errors.TypingError):
        jit(nrt=False, cache=False)(allocates)(3)
    assert jit(cache=False)(allocates)(3) == 0.0


# Every compiled function of the step loop that takes arrays and is not inline="always"
# (inlined ones are compiled as part of their caller).
INLINED = (integrator.rk4_step, rigid_body.state_derivative, loop._sense, sensor_step.sensors_step,
           controller.position_stage, controller.attitude_stage, controller.actuate, controller.record_decision,
           plugin_step.plugin_control, plugin_step._apply, kernel.strategy_kernel)
STEP_LOOP = (
    loop.run_steps, loop._log_row,
    # rk4_step, state_derivative, loop._sense, sensor_step.sensors_step and the control stages are
    # inline="always" (a call passed their namedtuples field by field every step or control step,
    # docs/explanation/performance.md)
    integrator.apply_ground, ground.hold_on_ground,
    disturbances.wind_force, disturbances.shock_torque, disturbances.extra_mass_effects,
    rotation.quat_normalize, rotation.quat_to_rot, rotation.quat_derivative,
    plugin_step._control, plugin_step._observe, plugin_step._invoke, 
    kernel.position_laws, kernel.attitude_laws,
    runner.guidance_update, runner._waypoints, runner._start_leg, runner._advance, runner.start_at,
    trajectories.helix_eq46, trajectories.harmonic_attitude, waypoint_switching.line_setpoint,
    imu_module._sample_imu_modules, supervisor.supervise,
    # called, not inlined (the cold compile)
    attitude_pipeline.attitude_estimation_step,
    load_cell_filter.load_cell_filter_step, onboard_position.onboard_translation_step, smc.smc_attitude,
    fuzzy.flc_eval, fuzzy.flc_axis, allocation.allocate, pid.pid_axis, complementary.complementary_step,
    ensemble.ensemble_step, ensemble.ensemble_vectors, imu_calibration.apply_imu_calibration,
    reference_filter.reference_step, controller.shape_attitude,
)


@pytest.mark.parametrize("dispatcher", STEP_LOOP, ids=lambda d: d.py_func.__qualname__)
def test_step_loop_functions_are_compiled_without_reference_counting(dispatcher):
    assert dispatcher.targetoptions["_nrt"] is False


@pytest.mark.parametrize("dispatcher", INLINED, ids=lambda d: d.py_func.__qualname__)
def test_the_inlined_step_loop_functions_are_inlined(dispatcher):
    # they take the reference-counting flag of the function they are inlined into
    assert dispatcher.targetoptions["inline"] == "always"


@jit(cache=False, nrt=False)
def _draws(bits, out):
    rng = rng_bits.generator(bits)
    for i in range(out.shape[0]):
        out[i] = rng.standard_normal()


@pytest.mark.parametrize("seed", [0, 7])
def test_the_loop_draws_the_generator_numbers_from_its_pointers_or_its_bit_generator(seed):
    # rng_bits.pointers: the bit generator as five integers, read once; numba's Generator rebuilt
    # over them draws the numbers of the Python generator and advances its state in place
    ref = np.random.default_rng(seed)
    expected = ref.standard_normal(64)
    for arg in (rng_bits.pointers, lambda b: b):
        rng = np.random.default_rng(seed)
        out = np.zeros(32)
        _draws(arg(rng.bit_generator), out)
        assert np.array_equal(out, expected[:32])
        assert np.array_equal(rng.standard_normal(32), expected[32:])  # the state moved in place
    bits = np.random.default_rng(seed).bit_generator
    assert rng_bits.pointers(bits) == rng_bits.pointers(bits)  # fixed for the bit generator's life


def test_entry_point_takes_the_bit_generator_and_keeps_no_reference():
    # an nrt=False function called from Python with a Generator would keep one reference to
    # it per call: the step loop takes its bit generator's pointers (rig_emulator/simulation/rng_bits.py);
    # sample_imu_modules, called from Python with a Generator, keeps NRT for that reason
    assert imu_module.sample_imu_modules.targetoptions["_nrt"] is True
    sim = Simulation(load_config(scenario="hover", overrides={"sim.duration": 1.0}))
    rng = sim.sensing.run_rng
    bits = rng.bit_generator
    sim.advance(5)  # compiles or loads the loop
    held = (rng, bits, sim.x, sim.log, sim.pp.hw, sim.sensing.state)  # a Generator, arrays, namedtuples
    before = [sys.getrefcount(a) for a in held]
    for _ in range(200):
        sim.advance(5)
    assert [sys.getrefcount(a) for a in held] == before
