"""What the Python API fuzz suite (test_fuzz_python_api.py) found, case by case: each call hung,
raised an undocumented exception, accepted a bool/NaN silently or wrote a message of 100 kB
before the checks at the public boundary; now it is refused at once with a one-line message
naming the parameter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gearvib.config import ConfigError
from gearvib.memory import RunSizeError


def _one_line(exc: BaseException, limit: int = 1000) -> str:
    text = str(exc)
    assert "\n" not in text and len(text) <= limit, text[:200]
    return text


@pytest.fixture(scope="module")
def model():
    from gearvib.assembly import assemble
    from gearvib.config import load_gearset

    return assemble(load_gearset("paper-case1"))


def _body(name, role="central"):
    from gearvib.structure import Body, Support

    return Body(name, role, 1.0, 1e-3, Support(), carrier="carrier" if role == "planet" else None)


def _spec():
    from gearvib.stiffness import ConstantStiffness
    from gearvib.structure import MeshSpec

    return MeshSpec(ConstantStiffness(3e8))


@pytest.mark.parametrize("n_planets", [10**18, 1e300])
def test_a_huge_planet_count_is_refused_at_once(n_planets):
    """It built 10^18 planet angles (hung)."""
    from gearvib.structure import simple_planetary

    with pytest.raises(ValueError, match=r"^n_planets") as info:
        simple_planetary(z_sun=33, z_ring=-114, z_planet=40, module=2.5e-3, sun=_body("sun"),
                         ring=_body("ring"), carrier=_body("carrier", "carrier"),
                         planet=_body("planet", "planet"), sun_mesh=_spec(),
                         ring_mesh=_spec(), n_planets=n_planets)
    _one_line(info.value)


def test_a_huge_candidate_order_is_refused(model):
    """n_max = 1e300 looped for ever (gearvib.stability and analysis.instability.theory)."""
    from analysis.instability.theory import instability_candidates
    from gearvib.stability import gear_set_candidates

    with pytest.raises(ValueError, match=r"^n_max"):
        gear_set_candidates(model, n_max=1e300)
    with pytest.raises(ValueError, match=r"^n_max = 1e\+300 is not admissible"):
        instability_candidates([100.0, 250.0], n_max=1e300)


def test_a_huge_stability_map_is_refused_before_the_floquet_work(model):
    """10^6 parameter values x 2 speeds ran for ever."""
    from gearvib.stability import stability_map

    with pytest.raises(ValueError, match=r"values x speeds_rpm: 1000000 x 2 points"):
        stability_map(lambda v: model, np.array([1000.0, 2000.0]), np.ones(10**6))


def test_a_fourier_stiffness_of_a_million_harmonics_is_refused():
    """It evaluated 10^6 harmonics at 8192 points (hung)."""
    from gearvib.stiffness import FourierStiffness

    with pytest.raises(ValueError, match=r"^cos: 1000000 coefficients"):
        FourierStiffness(3e8, np.ones(10**6))


def test_gyroscopic_must_be_a_bool_in_a_batch(model):
    """gyroscopic = -1 compiled another batched kernel (more than 30 s)."""
    from gearvib.simulate import SpeedRamp, simulate_batch

    with pytest.raises(TypeError, match=r"^gyroscopic must be a bool"):
        simulate_batch([model], SpeedRamp(1000.0, 1000.0, 0.002, input_torque=60.0),
                       gyroscopic=-1, max_steps=20_000)


def test_config_of_a_run_is_checked_before_the_run(model):
    """A config that is not JSON text failed with JSONDecodeError after the whole run."""
    from gearvib.simulate import SpeedRamp, simulate

    with pytest.raises(ValueError, match=r"^config is not JSON text"):
        simulate(model, SpeedRamp(1000.0, 1000.0, 0.002, input_torque=60.0),
                 config="paper-case1", max_steps=20_000)
    with pytest.raises(ValueError, match=r"^natural_frequencies"):
        simulate(model, SpeedRamp(1000.0, 1000.0, 0.002, input_torque=60.0),
                 natural_frequencies=[math.nan], max_steps=20_000)


def test_the_decimation_filter_checks_its_size_first():
    """A decimation of 10^14 allocated 2.7e15 taps (MemoryError); 10^320 overflowed."""
    from gearvib.simulation.decimation import decimation_filter

    with pytest.raises(RunSizeError, match=r"decimation filter of decimation = 100000000000000"):
        decimation_filter(10**14)
    with pytest.raises(ValueError, match=r"^decimation"):
        decimation_filter(10**320)


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({"start_rpm": True}, ValueError, r"^start_rpm \[min-1\] must be a number, got True"),
    ({"start_rpm": math.nan}, ValueError, r"^start_rpm \[min-1\] = nan is not admissible"),
    ({"end_rpm": "1000"}, ValueError, r"^end_rpm \[min-1\] must be a number, got '1000'"),
    ({"load_torque": math.inf}, ValueError, r"^load_torque \[N m\] = inf"),
    ({"input_torque": 10**320}, ValueError, r"^input_torque \[N m\] = 10000000000000000000"),
    ({"coupling": 1.0}, TypeError, r"^coupling must be a DriveCoupling"),
])
def test_speed_ramp_refuses_what_it_took_silently(kwargs, error, match):
    """SpeedRamp took bools, strings, NaN and inf (the run failed later or ran with them)."""
    from gearvib.simulate import SpeedRamp

    args = {"start_rpm": 1000.0, "end_rpm": 1000.0, "duration": 0.01, **kwargs}
    with pytest.raises(error, match=match) as info:
        SpeedRamp(**args)
    _one_line(info.value)


def test_numbers_beyond_a_float_and_out_of_range_are_refused():
    """OverflowError from float() before; a module of 1e300 m overflowed in the geometry."""
    from gearvib.geometry import Toothing
    from gearvib.kinematics import mesh_frequency

    with pytest.raises(ValueError, match=r"^module = 1e\+300 m is not admissible"):
        Toothing(33, 1e300)
    with pytest.raises(ValueError, match=r"^module = 1000000000000000000000000000000000000\.\.\. "
                       r"is not admissible"):
        Toothing(33, 10**320)
    with pytest.raises(ValueError, match=r"^n_central \[min-1\] = 1e\+300"):
        mesh_frequency(33, 1e300, 0.0)


def test_messages_cut_long_values():
    """A 100 000-character name or role was echoed whole (a 100 kB message)."""
    from gearvib.config import load_gearset
    from gearvib.structure import Body

    for call in (lambda: Body("x" * 100_000, "wrong", 1.0, 1.0),
                 lambda: load_gearset("y" * 100_000)):
        with pytest.raises(ValueError) as info:
            call()
        assert len(_one_line(info.value, 400)) < 400


def test_settings_objects_check_their_fields():
    """AnalysisSettings, RunSettings and the sweep's SummarySettings took NaN, inf and bools
    (only their TOML readers checked)."""
    from gearvib.report import AnalysisSettings, RunSettings
    from gearvib.sweep import SummarySettings

    with pytest.raises(ConfigError, match=r"^AnalysisSettings\.n_max = 1\.5; admissible"):
        AnalysisSettings(n_max=1.5)
    with pytest.raises(ConfigError, match=r"^AnalysisSettings\.map_resolution_hz"):
        AnalysisSettings(map_resolution_hz=math.inf)
    with pytest.raises(ConfigError, match=r"^RunSettings\.duration"):
        RunSettings(duration=math.nan)
    with pytest.raises(ConfigError, match=r"^SummarySettings\.orders must be"):
        SummarySettings(orders=(1.0, math.nan))


def test_a_measured_frf_must_be_finite():
    """MeasuredFrf took NaN frequencies and values (its accelerance was NaN)."""
    from gearvib.sensors import MeasuredFrf, SensorError

    with pytest.raises(SensorError, match=r"frf '': frequency: non-finite value"):
        MeasuredFrf((100.0, math.nan), (1e-3, 1e-3), (0.0, 0.0))


def test_a_failed_write_into_proc_is_not_a_full_disk(tmp_path):
    """/proc has no free bytes: a write refused there was reported as 'No space left on
    device'."""
    from gearvib.io import atomic_write

    with pytest.raises(OSError) as info:
        atomic_write("/proc/self/gearvib-test", lambda p: p.write_text("x"))
    assert "No space left" not in str(info.value)


def test_wrong_classes_are_named(model):
    """A gear set where a model is expected raised AttributeError deep inside."""
    from gearvib.assembly import assemble
    from gearvib.config import load_gearset
    from gearvib.modal import modal_analysis
    from gearvib.simulate import SpeedRamp, simulate

    with pytest.raises(TypeError, match=r"^model must be a gearvib\.model\.AssembledModel; "
                       r"got GearSet"):
        modal_analysis(load_gearset("paper-case1"))
    with pytest.raises(TypeError, match=r"^gs must be a GearSet; got AssembledModel"):
        assemble(model)
    with pytest.raises(TypeError, match=r"^model must be"):
        simulate("paper-case1", SpeedRamp(1000.0, 1000.0, 0.002))
