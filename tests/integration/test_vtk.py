"""VTK export (``--vtk`` on solve, sequence and simulate): the files read back with meshio give
the solution's centerline, frames, internal forces, tensions and temperatures to 1e-12, obstacles
and objects as closed surfaces where they are, and a simulate run's .pvd lists every output
time."""
import json

import meshio
import numpy as np
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.cli import main
from tca_casadi.time_simulation.timeline import TimeSimulation
from tca_casadi.vtk_files import read_collection, write_series


def _frame(directory, stem="vtk_0000"):
    return {part: meshio.read(directory / f"{stem}_{part}.vtu") for part in ("rods", "actuators", "surfaces")
            if (directory / f"{stem}_{part}.vtu").exists()}


def assert_round_trip(solution, grids):
    rods, actuators = grids["rods"], grids["actuators"]
    assert_allclose(rods.points, np.hstack([m.p for m in solution.modules]).T, rtol=0, atol=1e-12)
    data = rods.point_data
    assert_allclose(data["arc_length_m"], np.concatenate([m.s for m in solution.modules]), rtol=0, atol=1e-12)
    assert_allclose(data["d3"], np.hstack([m.R[:, 2, :] for m in solution.modules]).T, rtol=0, atol=1e-12)
    assert_allclose(data["force_N"], np.hstack([m.force for m in solution.modules]).T, rtol=0, atol=1e-12)
    assert_allclose(data["curvature_per_m"], np.hstack([m.u for m in solution.modules]).T, rtol=0, atol=1e-12)
    assert len(rods.cells_dict["line"]) == sum(m.p.shape[1] - 1 for m in solution.modules)
    index = actuators.cell_data["actuator"][0]
    for k, actuator in enumerate(solution.actuators.values()):
        tensions = actuators.cell_data["tension_N"][0][index == k]
        assert tensions.size == actuator.path.shape[1] - 1
        assert_allclose(tensions, actuator.tension, rtol=0, atol=1e-12 * max(1.0, abs(actuator.tension)))
        temperatures = actuators.cell_data["temperature_degC"][0][index == k]
        if actuator.temperature is None:
            assert np.all(np.isnan(temperatures))
        else:
            assert_allclose(temperatures, actuator.temperature, rtol=0, atol=1e-12)


def test_solve_vtk_round_trip_and_an_obstacle_surface(tmp_path):
    """The tendon robot against its wall (a box obstacle): the rods and tendons back to 1e-12, the
    wall as 6 quadrilaterals on its corners, the names beside them; a second solve without
    --vtk leaves no VTK file of the first (the directory holds one run's set)."""
    scenario = SCENARIOS / "tendon_robot_wall.yaml"
    assert main(["solve", str(scenario), "-o", str(tmp_path), "--no-plot", "--vtk"]) == 0
    solution = Simulation.from_file(scenario).solve(warn=False)
    grids = _frame(tmp_path)
    assert_round_trip(solution, grids)
    names = json.loads((tmp_path / "solution_names.json").read_text())
    assert names["actuator"] == list(solution.actuators) and names["module"] == [m.name for m in solution.modules]
    surfaces = grids["surfaces"]
    assert names["surface"] == [shape.name for shape in solution.obstacles]
    wall = solution.obstacles[0]
    assert type(wall).__name__ == "Box" and len(surfaces.cells_dict["quad"]) == 6
    local = (surfaces.points - wall.position) @ wall.rotation
    assert_allclose(np.abs(local), np.tile(np.asarray(wall.size) / 2, (8, 1)), rtol=0, atol=1e-12)
    assert [t for t, _, _ in read_collection(tmp_path / "solution.pvd")] == [0.0] * 3
    assert main(["solve", str(scenario), "-o", str(tmp_path), "--no-plot"]) == 0
    assert not list(tmp_path.glob("vtk_*")) and not (tmp_path / "solution.pvd").exists()


def test_simulate_vtk_lists_every_output_time_and_round_trips(tmp_path):
    """A heating cycle at 10 s outputs: the .pvd lists each part at every output time of
    timeseries.csv, each file exists, and the frames written in-process give each time's
    solution back (TCA 2's temperature as it heats and cools) to 1e-12."""
    heating = SCENARIOS / "bending_module_heating.yaml"
    assert main(["simulate", str(heating), "--dt", "10", "--vtk", "--no-plot", "--no-animation", "--quiet",
                 "-o", str(tmp_path / "cli")]) == 0
    times = np.genfromtxt(tmp_path / "cli" / "timeseries.csv", delimiter=",", names=True)["t_s"]
    listed = read_collection(tmp_path / "cli" / "simulate.pvd")
    for part in (0, 1):
        assert_allclose([t for t, p, _ in listed if p == part], times, rtol=0, atol=1e-12)
    assert all(path.exists() for _, _, path in listed)
    series = TimeSimulation(Simulation.from_file(heating), dt=10.0).run()
    write_series(zip(series.t, series.solutions, [()] * len(series.t)), tmp_path, "simulate")
    for k, solution in enumerate(series.solutions):
        assert_round_trip(solution, _frame(tmp_path, f"vtk_{k:04d}"))
    assert len({s.actuators["bending.tca2"].temperature for s in series.solutions}) > 3       # it heats and cools


def test_sequence_vtk_has_the_objects_where_the_sequence_puts_them(tmp_path):
    """The pick-and-place: a frame per step, the bar's box at its pose of that step."""
    from tca_casadi.studies.sequence.steps import run_sequence
    scenario = SCENARIOS / "arm_pick_and_place.yaml"
    result = run_sequence(Simulation.from_file(scenario))
    write_series([(float(k), s, result.objects[k]) for k, s in enumerate(result.solutions)], tmp_path, "sequence")
    for k in (0, len(result.solutions) - 1):
        grids = _frame(tmp_path, f"vtk_{k:04d}")
        assert_round_trip(result.solutions[k], grids)
        (name, pose), = result.objects[k].items()
        assert_allclose(grids["surfaces"].points, pose.corners().T, rtol=0, atol=1e-12)
    assert json.loads((tmp_path / "sequence_names.json").read_text())["surface"] == [name]


def test_vtk_of_a_closed_loop_is_refused(tmp_path, capsys):
    assert main(["simulate", str(SCENARIOS / "bending_module_mpc.yaml"), "--vtk", "-o", str(tmp_path), "--quiet"]) == 2
    assert "--vtk: a closed loop" in capsys.readouterr().err
