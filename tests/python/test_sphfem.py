"""The Python module: every binding, its errors, and its arrays against the CLI's frames."""

import gc
import json

import numpy as np
import pytest

import sphfem
from conftest import SOURCE, cli, read_ply

FRAME = 1 / 30  # the cup scene's output.fps


def test_scene_from_a_file_or_a_dict_runs_the_same(cup, cup_file):
    a = sphfem.Simulation(cup_file)
    b = sphfem.Simulation(cup, backend="cpu", threads=2)  # the same bits on any thread count
    assert a.scene == b.scene
    a.advance(2 * FRAME)
    b.advance(2 * FRAME)
    assert a.state_hash() == b.state_hash()
    assert a.time == pytest.approx(2 * FRAME)
    assert a.steps == b.steps > 0
    assert a.bodies == ["cup"]


def test_bad_scene_raises_the_clis_message_with_the_fields_path(cup, tmp_path):
    cup["fluid"]["particle_radius"] = -1
    with pytest.raises(sphfem.SceneError) as dict_error:
        sphfem.Simulation(cup, path="bad.json")
    assert "fluid.particle_radius" in str(dict_error.value)
    assert isinstance(dict_error.value, ValueError)

    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(cup))
    code, out = cli("check", bad)
    assert code == 2
    with pytest.raises(sphfem.SceneError) as file_error:
        sphfem.Simulation(bad)
    assert out.strip() == "error: " + str(file_error.value)
    with pytest.raises(sphfem.SceneError, match="file not found"):
        sphfem.load_scene(tmp_path / "missing.json")
    with pytest.raises(ValueError, match="backend"):
        sphfem.Simulation(SOURCE / "scenes/dam_break.json", backend="tpu")


def test_arrays_match_the_clis_frames_for_the_same_steps(cup, tmp_path):
    cup["output"]["ply"] = True
    scene = tmp_path / "cup.json"
    scene.write_text(json.dumps(cup))
    out = tmp_path / "run"
    code, text = cli("run", scene, "--out", out, "--duration", 4 * FRAME)
    assert code == 0, text

    sim = sphfem.Simulation(scene)
    sim.advance(4 * FRAME)
    # Same steps, same bits: the CLI prints the final state's hash.
    assert sim.state_hash() in text
    frame = read_ply(out / "frames/fluid_000004.ply")
    assert sim.n_particles == len(frame) > 0
    np.testing.assert_array_equal(sim.positions, np.stack([frame["x"], frame["y"], frame["z"]], 1))
    np.testing.assert_array_equal(
        sim.velocities, np.stack([frame["velocity_x"], frame["velocity_y"], frame["velocity_z"]], 1))
    np.testing.assert_array_equal(sim.densities, frame["density"])
    np.testing.assert_array_equal(sim.pressures, frame["pressure"])
    np.testing.assert_array_equal(sim.ids, frame["id"])

    # The gauges: gauges.csv's columns of the same names, at the same frames.
    csv = np.genfromtxt(out / "gauges.csv", delimiter=",", names=True)
    gauges = sim.gauges
    assert len(gauges["time"]) == len(csv) == 5
    for name in ["time", "step", "n_fluid", "kinetic_energy", "cup_rim_dx", "cup_rim_dy",
                 "cup_elastic_energy", "inside_bodies"]:
        np.testing.assert_allclose(gauges[name], csv[name], rtol=1e-8, atol=1e-12, err_msg=name)


def test_arrays_have_their_shapes_and_are_read_only(cup):
    sim = sphfem.Simulation(cup)
    sim.advance(3 * FRAME)
    n, nodes = sim.n_particles, len(sim.rest_positions)
    assert n > 0 and nodes > 0
    assert sim.positions.shape == sim.velocities.shape == (n, 3)
    assert sim.densities.shape == sim.pressures.shape == sim.ids.shape == (n,)
    assert sim.body_positions.shape == sim.body_velocities.shape == (nodes, 3)
    assert len(set(sim.ids.tolist())) == n
    assert np.all(sim.densities > 0)
    rim = sim.body_nodes("cup")
    assert rim == sim.body_nodes(0) == slice(0, nodes, 1)
    for a in [sim.positions, sim.densities, sim.body_positions]:
        assert not a.flags.writeable
        with pytest.raises(ValueError):
            a[0] = 0
    with pytest.raises(KeyError, match="cup"):
        sim.body_nodes("mug")


def test_step_ends_on_frame_times_and_reports_the_step(cup):
    sim = sphfem.Simulation(cup)
    info = sim.step()
    assert set(info) == {"dt", "pressure_iterations", "divergence_iterations", "density_error",
                         "clamped", "emitted"}
    assert 0 < info["dt"] <= cup["simulation"]["dt_max"]
    assert sim.step(dt=1e-4)["dt"] == pytest.approx(1e-4)
    while len(sim.gauges["time"]) < 2:
        sim.step()
    assert sim.time == pytest.approx(FRAME, abs=1e-12)
    np.testing.assert_allclose(sim.gauges["time"], [0, FRAME], atol=1e-12)


def test_views_outlive_the_simulation(cup):
    sim = sphfem.Simulation(cup)
    sim.advance(2 * FRAME)
    x, rho = sim.positions, sim.densities
    nodes = sim.body_positions
    x0, nodes0 = x.copy(), nodes.copy()
    # The fluid's arrays keep the state they were read at; the bodies' follow the simulation.
    sim.advance(FRAME)
    np.testing.assert_array_equal(x, x0)
    assert sim.positions.shape != x.shape or np.any(sim.positions != x)
    np.testing.assert_array_equal(nodes, sim.body_positions)
    assert np.any(nodes != nodes0)
    del sim
    gc.collect()
    np.testing.assert_array_equal(x, x0)
    assert np.all(rho > 0)
    assert np.isfinite(nodes).all()


def test_emitters_turn_off_and_on(cup):
    sim = sphfem.Simulation(cup)
    assert sim.emitter_on(0)
    sim.set_emitter(0, False)
    assert not sim.emitter_on(0)
    sim.advance(2 * FRAME)
    assert sim.n_particles == 0
    sim.set_emitter(0, True)
    sim.advance(FRAME)
    assert sim.n_particles > 0
    with pytest.raises(IndexError, match="emitters"):
        sim.set_emitter(1, True)


def test_moving_pinned_nodes_moves_the_body(cup):
    cup["fluid"]["emitters"] = []  # the cup alone
    sim = sphfem.Simulation(cup)
    pinned = sim.pinned_nodes("cup")
    rest = sim.rest_positions
    assert 0 < len(pinned) < len(rest)
    for k in range(1, 11):  # the base slides 10 mm along x, 1 mm a step
        sim.move_pinned(pinned, rest[pinned] + [0.001 * k, 0, 0])
        sim.step()
    sim.advance(0.2)
    dx = sim.body_positions[:, 0] - rest[:, 0]
    np.testing.assert_allclose(dx[pinned], 0.01, atol=1e-6)
    free = np.setdiff1d(np.arange(len(rest)), pinned)
    # The cup follows its base, the nodes resting on the floor held back by its friction; left
    # alone it stays where it was.
    assert 0.003 < dx[free].mean() < 0.012
    assert sim.gauges["cup_rim_dx"][-1] > 0.003
    still = sphfem.Simulation(cup)
    still.advance(sim.time)
    assert abs((still.body_positions[free, 0] - rest[free, 0]).mean()) < 0.0005
    with pytest.raises(ValueError, match="not pinned"):
        sim.move_pinned([int(free[0])], [[0, 0, 0]])
    with pytest.raises(ValueError, match="positions"):
        sim.move_pinned(pinned, [0, 0, 0])


def test_write_frame_writes_what_the_cli_writes(cup, tmp_path):
    cup["output"]["ply"] = True
    sim = sphfem.Simulation(cup)
    first = sim.write_frame(tmp_path)
    sim.advance(2 * FRAME)
    files = sim.write_frame(tmp_path)
    names = sorted(p.rsplit("/", 1)[1] for p in files)
    assert names == ["bodies_000001.vtu", "bodies_tets_000001.vtu", "fluid_000001.ply",
                     "fluid_000001.vtu"]
    assert len(first) == 4 and (tmp_path / "run.json").exists()
    for kind in ["fluid", "bodies", "bodies_tets"]:
        assert (tmp_path / f"{kind}.pvd").read_text().count("<DataSet") == 2
    frame = read_ply(tmp_path / "frames/fluid_000001.ply")
    np.testing.assert_array_equal(frame["x"], sim.positions[:, 0])


def test_save_and_load_continue_bit_for_bit(cup, tmp_path):
    sim = sphfem.Simulation(cup)
    sim.advance(2 * FRAME)
    sim.save(tmp_path / "state.bin")
    sim.advance(2 * FRAME)
    want = sim.state_hash()

    other = sphfem.Simulation(cup)
    other.load(tmp_path / "state.bin")
    assert other.time == pytest.approx(2 * FRAME)
    other.advance(2 * FRAME)
    assert other.state_hash() == want

    cup["bodies"][0]["material"]["young"] = 3e5
    with pytest.raises(sphfem.CheckpointError, match="another scene"):
        sphfem.Simulation(cup).load(tmp_path / "state.bin")
    damaged = tmp_path / "damaged.bin"
    damaged.write_bytes((tmp_path / "state.bin").read_bytes()[:100])
    with pytest.raises(sphfem.CheckpointError):
        sim.load(damaged)


def test_an_unstable_run_raises_simulation_error():
    scene = {
        "simulation": {"duration": 1.0, "solver": "wcsph", "dt_min": 0.0012, "dt_max": 0.0012,
                       "cfl": 1.0},
        "fluid": {"particle_radius": 0.01, "stiffness": 200000,
                  "blocks": [{"min": [0, 0, 0], "max": [0.1, 0.3, 0.1]}]},
        "domain": {"min": [0, 0, 0], "max": [0.5, 0.4, 0.1]},
        "output": {"fps": 100},
    }
    sim = sphfem.Simulation(scene)
    with pytest.raises(sphfem.SimulationError, match="step"):
        sim.advance(1.0)


def test_load_scene_returns_every_field(cup):
    assert cup["bodies"][0]["name"] == "cup"
    assert "dt_max" in cup["simulation"] and "emitters" in cup["fluid"]
