"""Scenario builders shared by the integration tests (dicts, as a user would write YAML)."""
from tca_casadi import Simulation

HANG = {"position": [0, 0, 0], "orientation": {"axis": [1, 0, 0], "angle": "180 deg"}}
TCA_TYPE = {"nylon": {"fiber_radius": "0.5 mm", "coil_radius": "0.6 mm", "pitch_angle": "30 deg"}}


def rod(name, length, actuators=(), **extra):
    return dict({"name": name, "length": length, "material": "ecoflex",
                 "cross_section": {"shape": "circle", "diameter": "4.5 mm",
                                   "envelope": {"shape": "circle", "diameter": "10 mm"}},
                 "actuators": list(actuators)}, **extra)


def robot(modules, loads=(), gravity=(0, 0, -9.81)):
    return {"name": "chain", "gravity": list(gravity), "base": HANG,
            "materials": {"ecoflex": {"youngs_modulus": "0.125 MPa", "density": "1070 kg/m^3"}},
            "tca_types": TCA_TYPE, "modules": list(modules), "loads": list(loads),
            "solver": {"intervals": 12, "degree": 4}}


def tca(name, angle, temperature, span=None):
    route = {"kind": "straight", "radius": "4 mm", "angle": angle}
    if span is not None:
        route["span"] = span
    return {"name": name, "kind": "tca", "type": "nylon", "route": route, "temperature": temperature}


def solve(scenario):
    solution = Simulation.from_file(scenario).solve()
    assert solution.converged, solution.message
    return solution


def mixed_chain(intervals, refine="auto"):
    chain = robot([rod("bend", "30 mm", [tca("a", "0 deg", 80), tca("b", "180 deg", 25)]),
                   rod("twist", "16 mm", [{"name": "h", "kind": "tca", "type": "nylon", "temperature": 90,
                                           "route": {"kind": "helix", "radius": "3.5 mm", "turns": 3,
                                                     "span": ["2 mm", "14 mm"]}}]),
                   rod("tail", "20 mm", [{"name": "c", "kind": "tendon", "tension": "5 mN",
                                          "route": {"kind": "curve", "points": [[0, 0.001, 0], [0.01, 0.002, 0.001],
                                                                                [0.02, 0.0, 0.002]]}}])],
                  loads=[{"name": "payload", "kind": "mass", "module": "tail", "mass": "1 g"}])
    chain["solver"]["intervals"] = intervals
    chain["solver"]["refine"] = refine
    return Simulation.from_file(chain)
