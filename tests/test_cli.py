"""The `gearjax` command: default scene, JSON keys, scene files and their errors."""

import json
import math

import pytest

from gearjax.cli import main
from gearjax.ltca import iso_mesh_stiffness


@pytest.fixture(scope="module")
def default_json():
    import contextlib
    import io

    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        assert main(["run", "--json"]) == 0
    return json.loads(buffer.getvalue())


def test_default_scene_json_has_the_documented_keys(default_json, seed_pair):
    g, t = default_json["geometry"], default_json["tca"]
    assert g["base_radius_mm"] == pytest.approx([float(v) for v in seed_pair.base_radius], rel=1e-12)
    assert len(g["base_radius_mm"]) == 2
    assert g["center_distance_mm"] == pytest.approx(281.8454867, rel=1e-9)
    assert g["working_pressure_angle_deg"] == pytest.approx(22.30998, abs=1e-5)
    assert g["transverse_contact_ratio"] == pytest.approx(1.4523, abs=1e-4)
    assert g["overlap_ratio"] == pytest.approx(1.2346, abs=1e-4)
    rb2 = g["base_radius_mm"][1]
    assert t["te_peak_to_peak_um"] == pytest.approx(t["te_peak_to_peak_urad"] * rb2 * 1e-3, rel=1e-12)
    assert max(t["te_urad"]) - min(t["te_urad"]) == pytest.approx(t["te_peak_to_peak_urad"], rel=1e-12)
    assert len(t["te_um"]) == t["positions"] == 32
    assert any("261.0" in note for note in default_json["notes"])


def test_default_scene_json_has_the_ltca_keys(default_json, seed_pair):
    lt, g = default_json["ltca"], default_json["geometry"]
    rb1 = g["base_radius_mm"][0]
    beta_b = math.radians(g["base_helix_angle_deg"])
    # The torque the JSON reports (both places, N·m) is the one the LTCA carried: the normal
    # load balances it on the moment arm r_b1 cos(beta_b) (exact for perfect flanks; the
    # modified flanks' normals tilt slightly and edge contacts have other arms: 1e-4 here)...
    for torque_Nm in (lt["torque_Nm"], default_json["operating"]["torque_Nm"]):
        assert lt["normal_load_N"] * rb1 * math.cos(beta_b) == pytest.approx(torque_Nm * 1e3, rel=1e-4)
    # ...and the mean elastic approach LTE - TE along the line of action (um) is that
    # torque's transverse load F_t = T/r_b1 over ISO 6336-1's mesh stiffness, b c_gamma_alpha,
    # within 20 % (the slice model is not ISO's: 9 % apart here).
    iso = float(iso_mesh_stiffness(seed_pair).mesh_stiffness)  # N/(mm um)
    approach_um = default_json["tca"]["te_mean_um"] - lt["lte_mean_um"]
    torque_Nmm = default_json["operating"]["torque_Nm"] * 1e3
    assert approach_um == pytest.approx(torque_Nmm / rb1 / (g["face_width_mm"] * iso), rel=0.2)
    assert lt["lte_peak_to_peak_um"] == pytest.approx(max(lt["lte_um"]) - min(lt["lte_um"]), rel=1e-9)
    assert 0.5 < lt["max_load_share"] <= 1.0
    assert 5.0 < lt["mean_mesh_stiffness_N_per_mm_um"] < 40.0
    assert lt["converged"] and lt["compliance"] == "SliceCompliance"
    assert lt["result"] == "successful" and default_json["tca"]["result"] == "successful"


def test_default_scene_json_has_the_impact_keys(default_json):
    im = default_json["impact"]
    assert im["regime"] in ("edge", "surface")
    assert (im["regime"] == "edge") == (im["contact_kind"] != "flank")
    assert len(im["point_mm"]) == 3 and len(im["normal"]) == 3
    assert math.isclose(sum(v * v for v in im["normal"]), 1.0, rel_tol=1e-9)
    # the strike point lies on the pinion flank: its radius matches its roll length up to
    # the modification depth there (crowning + root relief, < 15 um)
    x, y, _ = im["point_mm"]
    rb1 = default_json["geometry"]["base_radius_mm"][0]
    assert math.hypot(x, y) == pytest.approx(math.hypot(rb1, im["pinion_roll_length_mm"]), abs=0.015)
    assert im["velocity_mm_per_s"] > 0 and im["force_N"] > 0
    # energy method: F = K delta^n at the peak approach
    k, n = im["stiffness_coefficient_N_per_mm_n"], im["stiffness_exponent"]
    assert im["force_N"] == pytest.approx(k * (im["approach_um"] * 1e-3) ** n, rel=1e-9)
    assert im["converged"] and im["result"] == "successful"


def test_summary_is_readable(capsys):
    assert main(["run"]) == 0
    out = capsys.readouterr().out
    assert "centre distance" in out and "281.845" in out and "TE peak-to-peak" in out
    assert "Mesh-in impact" in out and "impact force" in out
    assert "inconsistent" in out  # the paper's centre distance note
    # in an engineer's words: no class names, whole labels, the TE's sign convention
    assert "GearPair" not in out and "Compliance" not in out, out
    assert "working pressure angle" in out and "involute helical gear pair" in out
    assert out.count("negative: the gear behind its rigid position") == 2
    assert "conjugate" in out  # the paper optimum's unloaded TE is zero: said why


def test_scene_file_with_modification_and_spur_pair(tmp_path, capsys):
    path = tmp_path / "spur.toml"
    path.write_text(
        """
[pair]
teeth = [23, 41]
normal_module = 4.0
pressure_angle_deg = 20.0
face_width = 20.0

[modification]
tip_relief_um = 10.0
tip_relief_length = 10.0

[operating]
speed_rpm = 3000.0

[analysis]
accuracy = "fast"
"""
    )
    assert main(["run", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # a speed without the impact stage is not silently ignored
    assert any("speed_rpm" in note and 'effects = ["impact"]' in note for note in out["notes"]), out.get("notes")
    assert out["geometry"]["helix_angle_deg"] == 0.0
    assert out["geometry"]["overlap_ratio"] == 0.0
    # pinion tip relief on a spur pair: a TE dip no deeper than the plane-of-action theory
    # C_a ((L_a - (eps_alpha - 1) p_bt) / L_a)^2; the coarse grid and the incoming pair's
    # edge contact make it shallower
    g = out["geometry"]
    theory = 10.0 * ((10.0 - (g["transverse_contact_ratio"] - 1) * g["transverse_base_pitch_mm"]) / 10.0) ** 2
    assert 0.3 * theory < out["tca"]["te_peak_to_peak_um"] <= theory


@pytest.mark.parametrize(
    "text, field",
    [
        ("[pair]\nteeth = [29, 71]\nnormal_module = 5.0\ncolour = 'red'\n", "[pair] colour:"),
        ("[pair]\nteeth = [29]\nnormal_module = 5.0\n", "[pair] teeth:"),
        ("[pair]\nteeth = [29, 71]\nnormal_module = 'five'\n", "[pair] normal_module:"),
        ("[pair]\nteeth = [29, 71]\n", "[pair] normal_module:"),
        ("[operating]\ntorque_Nm = 100\n", "[pair] missing section"),
        ("[pair]\nteeth = [3, 71]\nnormal_module = 5.0\n", "[pair] teeth[0] (pinion): must be"),
        ("[pair]\nteeth = [29, 71]\nnormal_module = 5.0\n[modification]\ntip_relief_um = -2\n", "[modification] tip_relief_um: must be in [0, 1000] µm; got -2 µm"),
        ("[pair]\nteeth = [29, 71]\nnormal_module = 5.0\n[operating]\ntorque_Nm = -3\n", "[operating] torque_Nm: must be in [0, 1e+09] N·m"),
        ("[pair]\nteeth = [29, 71]\nnormal_module = 5.0\n[analysis]\naccuracy = 'best'\n", "[analysis] accuracy: must be"),
        ("[pair]\nteeth = [29, 71]\nnormal_module = 5.0\ncenter_distance = 261.0\n", "[pair] center_distance: "),
        ("[pair\nteeth = 1\n", "not valid TOML"),
        ("[pair]\nteeth = [29, 71]\nnormal_module = 5.0\n[impact]\ninertia_kg_m2 = [1.0]\n", "[impact] inertia_kg_m2:"),
        ("[pair]\nteeth = [29, 71]\nnormal_module = 5.0\n[analysis]\neffects = ['impact']\n", "[analysis] effects: 'impact' needs a torque"),
        ("[pair]\nteeth = [29, 71]\nnormal_module = 5.0\n[ltca]\ncompliance = 'fem'\n", "[ltca] compliance:"),
        ("[pair]\nteeth = [29, 71]\nnormal_module = 5.0\ntooth_trace_radius = 30.0\n", "[pair] tooth_trace_radius:"),
        ("[pair]\nfamily = 'curvilinear'\nteeth = [20, 30]\nnormal_module = 2.0\nface_width = 20.0\ntooth_trace_radius = 9.0\n", "[pair] tooth_trace_radius: "),
        ("[pair]\nfamily = 'curvilinear'\nteeth = [20, 30]\nnormal_module = 2.0\nhelix_angle_deg = 10.0\n", "[pair] helix_angle_deg:"),
        ("[pair]\nfamily = 'cycloid'\nteeth = [20, 30]\nnormal_module = 2.0\n", "[pair] family:"),
    ],
)
def test_bad_scene_files_give_one_line_and_status_2(tmp_path, capsys, text, field):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert err.startswith("gearjax: error:")
    assert field in err


def _one_error_line(capsys) -> str:
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert "\n" not in err and err.startswith("gearjax"), err
    return err


@pytest.mark.parametrize(
    "content, match",
    [
        (bytes(range(128, 256)), "not UTF-8 text"),
        (b"", "[pair] missing section"),
        (b"[pair]\nfamily = 'double_circular_arc'\nteeth = [20, 40]\nnormal_module = 3.0\nhelix_angle_deg = 15.0\n"
         b"face_width = 9223372036854775808\n", "[pair] face_width: over a cycle of 1 pitch(es) the contact spans"),
        (b"[pair]\nteeth = [20, 40]\nnormal_module = 3.0\nhelix_angle_deg = 15.0\nface_width = 1e308\n",
         "[pair] face_width: over a cycle of 1 pitch(es) the contact spans"),
    ],
    ids=["binary", "empty", "dca-huge-face", "helical-huge-face"],
)
def test_unreadable_or_absurd_scene_files_give_one_line_and_status_2(tmp_path, capsys, content, match):
    path = tmp_path / "scene.toml"
    path.write_bytes(content)
    for command in (["run", str(path)], ["optimize", str(path), "--out", str(tmp_path / "run")]):
        assert main(command) == 2
        assert match in _one_error_line(capsys)


def test_a_directory_as_scene_is_a_clean_error(tmp_path, capsys):
    assert main(["run", str(tmp_path)]) == 2
    assert "cannot read the scene file" in _one_error_line(capsys)


@pytest.mark.parametrize("argv", [[], ["run", "--frob"], ["walk"], ["sweep", "--speed-rpm", "100"]])
def test_bad_arguments_give_one_line_and_status_2(capsys, argv):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert "; see gearjax" in _one_error_line(capsys)


def test_version_names_gearjax_and_jax(capsys):
    import jax

    import gearjax

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"gearjax {gearjax.__version__} (jax {jax.__version__}"), out


def test_missing_file_is_a_clean_error(capsys):
    assert main(["run", "/nonexistent/scene.toml"]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_working_pressure_angle_is_consistent(default_json):
    g = default_json["geometry"]
    a, rb = g["center_distance_mm"], g["base_radius_mm"]
    assert math.degrees(math.acos((rb[0] + rb[1]) / a)) == pytest.approx(g["working_pressure_angle_deg"], rel=1e-12)


def test_curvilinear_scene_file_and_reproduce(tmp_path, capsys):
    path = tmp_path / "curvilinear.toml"
    path.write_text(
        "[pair]\nfamily = 'curvilinear'\nteeth = [20, 30]\nnormal_module = 2.0\nface_width = 20.0\n"
        "tooth_trace_radius = 12.0\n[analysis]\npositions_per_pitch = 8\nface_slices = 5\n"
    )
    assert main(["run", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    g = out["geometry"]
    assert g["family"] == "CurvilinearGearPair" and g["tooth_trace_radius_mm"] == 12.0
    assert g["contact_line_length_mm"] == pytest.approx(24.0 * math.asin(10.0 / 12.0), rel=1e-12)
    assert g["center_distance_mm"] == pytest.approx(50.0, rel=1e-12)
    assert abs(out["tca"]["te_peak_to_peak_um"]) < 1e-9  # conjugate line contact

    assert main(["reproduce", "curvilinear", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["theta_t_prime"]["gearjax"] == pytest.approx(rep["theta_t_prime"]["paper"], abs=5e-5)
    for row in rep["contact_lines"]:
        assert row["all_slices_in_contact"] and row["max_distance_from_arc_mm"] < 1e-9
        assert row["length_mm"] == pytest.approx(row["closed_form_length_mm"], rel=1e-4)


def test_commands_use_the_persistent_cache_unless_told_not_to(tmp_path):
    """In a fresh process (where JAX has not yet decided on its cache), `optimize` and `run`
    turn JAX's persistent compilation cache on for their run, `--no-cache` turns it off; and each
    command leaves the setting as it found it."""
    import os
    import subprocess
    import sys

    script = (
        "import argparse, jax\n"
        "from gearjax.cli import _caches\n"
        "for command, no_cache in (('optimize', False), ('run', False), ('run', True)):\n"
        "    before = jax.config.jax_enable_compilation_cache\n"
        "    with _caches(argparse.Namespace(command=command, no_cache=no_cache)):\n"
        "        print(command, jax.config.jax_enable_compilation_cache, jax.config.jax_compilation_cache_dir)\n"
        "    assert jax.config.jax_enable_compilation_cache == before\n"
    )
    env = dict(os.environ, GEARJAX_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.splitlines()
    assert lines[0].split() == ["optimize", "True", str(tmp_path / "cache")]
    assert lines[1].split() == ["run", "True", str(tmp_path / "cache")]
    assert lines[2].split()[:2] == ["run", "False"]
