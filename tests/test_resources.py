"""The memory guard: a scene whose program cannot fit is refused before
anything is compiled, with the knobs and the estimate named; the estimate against XLA's own
memory plan of a scene that fits."""

import dataclasses

import numpy as np
import pytest

import gearjax.designs
import gearjax.pipeline
import gearjax.sweep.designs
import gearjax.sweep.loads
import gearjax.sweep.transition
from gearjax import Accuracy, OperatingPoint, Scene, design_sweep, impact_sweep, regime_transition, simulate, simulate_designs
from gearjax.geometry.modification import FlankModification
from gearjax.optimize import Objective
from gearjax.cli import main
from gearjax.papers.seed001 import paper_optimum
from gearjax.runtime.resources import MemoryEstimateError, check_memory, estimate_bytes
from gearjax.pipeline import prepare as _prepare, simulate_program as _simulate
from gearjax.io.scene_file import DEFAULT_SCENE_TOML
from gearjax.sweep import load_sweep


@pytest.fixture
def no_compute(forbid):
    """Fail if anything is compiled before the memory check."""
    forbid(gearjax.pipeline, "simulate_program")
    forbid(gearjax.sweep.loads, "_load_sweep")


def test_a_scene_that_cannot_fit_is_refused_before_compiling(seed_pair, no_compute, monkeypatch):
    """3000 face slices with a torque: ~69 GB of compliance blocks on the 24 GB machine
    (the limit is pinned so that the test does not depend on the machine)."""
    monkeypatch.setenv("GEARJAX_MEMORY_LIMIT_GB", "20")
    big = Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=1000.0),
                accuracy=Accuracy(face_slices=3000))
    with pytest.raises(MemoryEstimateError, match=r"face_slices = 3000 .*positions_per_pitch = 32") as info:
        simulate(big)
    assert isinstance(info.value, ValueError)
    needed = float(str(info.value).split("estimated ")[1].split(" GB")[0])
    assert needed == pytest.approx(estimate_bytes(big) / 1e9, abs=0.05) and needed > 20
    fits = int(str(info.value).split("at most ")[1].split(" fit")[0])
    check_memory(dataclasses.replace(big, accuracy=big.accuracy.replace(face_slices=fits)))  # the advice holds
    # the same slices without a torque: the TCA grows linearly and fits
    check_memory(Scene(seed_pair, accuracy=Accuracy(face_slices=3000)))
    # a load sweep multiplies the blocks by its loads, and says so
    scene = Scene(seed_pair, operating=OperatingPoint(torque_Nm=1000.0), accuracy=Accuracy(face_slices=401))
    check_memory(scene)
    with pytest.raises(MemoryEstimateError, match="for 64 loads at once"):
        load_sweep(scene, torques_Nm=np.linspace(0.0, 1000.0, 64))


@pytest.mark.parametrize("entry", ["simulate_designs", "impact_sweep", "design_sweep", "regime_transition",
                                   "objective"])
def test_every_entry_refuses_a_scene_that_cannot_fit_before_compiling(entry, seed_pair, forbid, monkeypatch):
    """The entries that run many designs or loads share `simulate`'s set-up (`launched`):
    each names itself and the knobs, and compiles nothing."""
    forbid(gearjax.designs, "_simulate_designs")
    forbid(gearjax.sweep.loads, "_impact_sweep")
    forbid(gearjax.sweep.designs, "_design_rows")
    forbid(gearjax.sweep.transition, "_transition")
    monkeypatch.setenv("GEARJAX_MEMORY_LIMIT_GB", "20")
    big = Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                effects=("impact",), accuracy=Accuracy(face_slices=3000))
    calls = {
        "simulate_designs": lambda: simulate_designs(big, [paper_optimum(), FlankModification()]),
        "impact_sweep": lambda: impact_sweep(big, torques_Nm=[500.0, 1000.0], speeds_rpm=[5000.0]),
        "design_sweep": lambda: design_sweep([big, big], torques_Nm=[1000.0]),
        "regime_transition": lambda: regime_transition(big, low_Nm=100.0, high_Nm=2000.0),
        "objective": lambda: Objective.create(big, torques_Nm=[400.0, 1000.0, 1600.0]),
    }
    name = "the objective" if entry == "objective" else entry
    with pytest.raises(MemoryEstimateError, match=rf"{name}.*face_slices = 3000"):
        calls[entry]()


def test_cli_run_refuses_the_scene_with_status_2(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("GEARJAX_MEMORY_LIMIT_GB", "20")
    path = tmp_path / "big.toml"
    path.write_text(DEFAULT_SCENE_TOML.replace('accuracy = "default"', 'accuracy = "default"\nface_slices = 3000'))
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "face_slices = 3000" in err[0] and "GB" in err[0], err


def test_estimate_is_within_a_factor_2_of_xlas_memory_plan(seed_pair):
    """At 61 slices (not one of the sizes the constants came from) the estimate against the
    compiled program's temporary and output buffers (`memory_analysis`)."""
    scene = Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=1000.0),
                  accuracy=Accuracy(face_slices=61))
    plan = _simulate.lower(_prepare(scene)).compile().compiled.memory_analysis()
    planned = plan.temp_size_in_bytes + plan.output_size_in_bytes
    assert 0.5 < estimate_bytes(scene) / planned < 2.0, (estimate_bytes(scene), planned)
