"""The figures of `gearjax.io.plot`: titled with their scene, drawn from result-shaped data
(no simulation: the plotted fields are given directly)."""

from types import SimpleNamespace

import equinox as eqx
import matplotlib  # the dev extra installs it: a missing install fails here instead of skipping
import numpy as np
import pytest

import gearjax as gj
from gearjax.optimize import OptimizationResult

matplotlib.use("Agg")
from gearjax.io import plot  # noqa: E402


def _spur_scene():
    pair = gj.InvoluteGearPair((20, 40), 3.0, face_width=30.0)
    return gj.Scene(pair, operating=gj.OperatingPoint(torque_Nm=200.0, speed_rpm=3000.0),
                    accuracy=gj.Accuracy(positions_per_pitch=24, face_slices=15))


def test_scene_title_names_the_pair_the_operating_point_and_the_accuracy():
    title = plot.scene_title(_spur_scene())
    assert title == "involute spur gear pair z 20/40, m_n 3 mm, b 30 mm; 200 N·m, 3000 rpm; 24 positions/pitch × 15 slices"
    rigid = plot.scene_title(gj.Scene(gj.DoubleArcGearPair((24, 24))))
    assert rigid.startswith("double-circular-arc gear pair (GB/T 12759) z 24/24, m_n 4 mm, b 55 mm; ")
    assert "N·m" not in rigid and "rpm" not in rigid
    assert plot.scene_title(_spur_scene(), operating=False) == (
        "involute spur gear pair z 20/40, m_n 3 mm, b 30 mm; 24 positions/pitch × 15 slices")
    assert plot.scene_title(_spur_scene(), operating=False, speed=True) == (
        "involute spur gear pair z 20/40, m_n 3 mm, b 30 mm; 3000 rpm; 24 positions/pitch × 15 slices")
    fast = eqx.tree_at(lambda s: s.operating, _spur_scene(), gj.OperatingPoint(torque_Nm=200.0, speed_rpm=12000.0))
    assert "; 200 N·m, 12000 rpm; " in plot.scene_title(fast)


def _fake_result():
    angle = np.linspace(0.0, 0.2, 8)
    share = np.stack([np.linspace(1.0, 0.0, 8), np.linspace(0.0, 1.0, 8)], axis=1)
    return SimpleNamespace(pinion_angle=angle, transmission_error_line=1e-3 * np.sin(angle), load_share=share,
                           pair_index=np.array([0, 1]), mesh_stiffness_tangent=np.full(8, 20.0),
                           mesh_stiffness_secant=np.full(8, 18.0))


def _history(method, certified):
    return OptimizationResult(method=method, best_design=np.zeros(6), best_objective=900.0, initial_objective=1200.0,
                              initial_design=np.zeros(6), history=[1100.0, 1000.0, 900.0], evaluations=30,
                              gradient_evaluations=0, steps=3, wall_time_s=1.0, converged=False, run_dir=None,
                              certified_objective=certified,
                              certification=None if certified is None else SimpleNamespace(accuracy="reference"))


@pytest.mark.parametrize("draw", [
    lambda t: plot.transmission_error(_fake_result(), title=t),
    lambda t: plot.loaded_transmission_error(_fake_result(), title=t),
    lambda t: plot.load_sharing(_fake_result(), title=t),
    lambda t: plot.mesh_stiffness(_fake_result(), title=t),
    lambda t: plot.impact_force_map([200.0, 600.0], [2000.0, 4000.0], [[1.0, 2.0], [3.0, 4.0]], title=t),
    lambda t: plot.regime_map([0.0, 10.0], [200.0, 600.0], [[1.0, 2.0], [3.0, 4.0]],
                              [["surface", "edge"], ["edge", "edge"]], title=t),
    lambda t: plot.harris_map([200.0, 600.0], [[1.0, 2.0]], title=t),
    lambda t: plot.optimisation_history([_history("ga", 950.0), _history("gradient", None)], title=t),
], ids=["te", "lte", "load_sharing", "stiffness", "force_map", "regime_map", "harris", "optimisation"])
def test_every_figure_takes_its_scene_as_title(draw, request):
    scene = _spur_scene()
    ax = draw(scene)
    kind = request.node.callspec.id
    swept = kind in ("force_map", "regime_map", "harris")  # over torque: no torque in the title
    speed = None if not swept else kind == "regime_map"  # the regime map is drawn at one speed
    assert ax.get_title() == plot.scene_title(scene, operating=not swept, speed=speed)
    matplotlib.pyplot.close(ax.figure)
    ax = draw(None)
    assert ax.get_title() == ""
    matplotlib.pyplot.close(ax.figure)


def test_optimisation_history_marks_the_certified_value_and_the_initial_design():
    ax = plot.optimisation_history([_history("ga", 950.0), _history("gradient", None)])
    labels = [line.get_label() for line in ax.lines]
    assert labels == ["ga: search", "ga: certified at 'reference'", "gradient: search", "initial design"]
    np.testing.assert_array_equal(ax.lines[0].get_xdata(), [10.0, 20.0, 30.0])
    np.testing.assert_array_equal(ax.lines[1].get_ydata(), [950.0])
    np.testing.assert_array_equal(ax.lines[-1].get_ydata(), [1200.0, 1200.0])
    matplotlib.pyplot.close(ax.figure)
