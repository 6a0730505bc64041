"""Random valid robots (scenario dicts, as a user would write them) for property tests: 1-3
modules in a chain or a tree, connectors, TCAs and tendons on straight, helical and spline routes
over random spans (anchors inside other actuators' spans), point loads, masses and distributed
loads in both frames, and gravity in any direction. Sizes are drawn so that the robot bends
visibly but moderately (loads a fraction of each module's ``EI / L^2``)."""
import math

import numpy as np

TCA_TYPE = {"fiber_radius": "0.3 mm", "coil_radius": "0.5 mm", "pitch_angle": "25 deg"}


def random_robot(seed):
    """A random valid scenario dict; the same ``seed`` gives the same robot."""
    rng = np.random.default_rng(seed)
    count = int(rng.integers(1, 4))
    modules = [_module(rng, k, count) for k in range(count)]
    loads = [load for k, module in enumerate(modules) for load in _loads(rng, module, k)]
    direction = rng.normal(size=3)
    return {"name": f"random_{seed}",
            "gravity": (rng.uniform(0, 9.81) * direction / np.linalg.norm(direction)).tolist(),
            "base": {"position": rng.uniform(-0.01, 0.01, 3).tolist(),
                     "orientation": {"axis": rng.normal(size=3).tolist(), "angle": float(rng.uniform(0, math.pi))}},
            "materials": {"soft": {"youngs_modulus": float(rng.uniform(0.1e6, 1e6)),
                                   "poisson_ratio": float(rng.uniform(0.3, 0.5)),
                                   "density": float(rng.uniform(1000, 1500))}},
            "tca_types": {"nylon": TCA_TYPE},
            "modules": [m["config"] for m in modules], "loads": loads}


def _module(rng, k, count):
    length = float(rng.uniform(0.02, 0.06))
    diameter = float(rng.uniform(0.006, 0.012))
    config = {"name": f"m{k}", "length": length, "material": "soft",
              "cross_section": {"shape": "circle", "diameter": diameter}, "actuators": []}
    if rng.random() < 0.3:
        config["cross_section"] = {"shape": "rectangle", "width": diameter, "height": diameter * 0.8}
        diameter *= 0.8
    if k > 0:
        if k == 2 and count == 3 and rng.random() < 0.5:
            config["parent"] = "m0"                  # a tree: two children on m0
        if rng.random() < 0.5:
            config["connector"] = {"offset": (rng.uniform(-1, 1, 3) * 0.002).tolist(),
                                   "rotation": {"axis": rng.normal(size=3).tolist(),
                                                "angle": float(rng.uniform(-0.5, 0.5))},
                                   "mass": float(rng.uniform(0, 0.002))}
    modulus = 0.5e6                                   # order of the drawn moduli, for sizing
    stiffness = modulus * math.pi * diameter**4 / 64
    for a in range(int(rng.integers(1, 4))):
        config["actuators"].append(_actuator(rng, a, length, diameter, stiffness))
    return {"config": config, "length": length, "force": stiffness / length**2}


def _actuator(rng, a, length, diameter, stiffness):
    radius = float(rng.uniform(0.1, 0.4) * diameter)
    span = sorted(rng.uniform(0, length, 2).tolist()) if rng.random() < 0.6 else None
    if span is not None and span[1] - span[0] < 0.2 * length:
        span = None
    kind = rng.choice(["straight", "helix", "curve"], p=[0.5, 0.3, 0.2])
    if kind != "curve":
        route = _placed_route(rng, kind, radius)
    else:
        s_a, s_b = span if span is not None else (0.0, length)
        s = np.linspace(s_a, s_b, 4)
        xy = rng.uniform(-1, 1, (4, 2)) * radius / math.sqrt(2)
        route = {"kind": "curve", "points": np.column_stack([s, xy]).tolist()}
        span = None                                   # a curve's span is its points' range
    if span is not None:
        route["span"] = span
    if rng.random() < 0.4:
        return {"name": f"t{a}", "kind": "tca", "type": "nylon", "route": route,
                "temperature": float(rng.uniform(25, 70))}
    tension = float(rng.uniform(0.05, 0.5) * stiffness / (length * max(radius, 1e-3)))
    return {"name": f"t{a}", "kind": "tendon", "route": route, "tension": tension}


def _placed_route(rng, kind, radius):
    """A straight route at a random angle, or a helix of random turns and phase, at ``radius``."""
    if kind == "straight":
        return {"kind": "straight", "radius": radius, "angle": float(rng.uniform(0, 2 * math.pi))}
    return {"kind": "helix", "radius": radius, "turns": float(rng.choice([-1, 1]) * rng.uniform(0.2, 1.5)),
            "phase": float(rng.uniform(0, 2 * math.pi))}


def _loads(rng, module, k):
    name, length, force = module["config"]["name"], module["length"], module["force"]
    out = []
    for j in range(int(rng.integers(0, 3))):
        kind = rng.choice(["point", "mass", "distributed"])
        label = f"{name}_{kind}{j}"
        at = float(rng.uniform(0.1, 1.0) * length) if rng.random() < 0.7 else "end"
        if kind == "point":
            out.append({"name": label, "kind": "point", "module": name, "at": at,
                        "force": (rng.normal(size=3) * 0.2 * force).tolist(),
                        "moment": (rng.normal(size=3) * 0.05 * force * length).tolist(),
                        "frame": str(rng.choice(["global", "body"]))})
        elif kind == "mass":
            out.append({"name": label, "kind": "mass", "module": name, "at": at,
                        "mass": float(rng.uniform(0, 0.2 * force / 9.81))})
        else:
            span = sorted(rng.uniform(0, length, 2).tolist())
            out.append({"name": label, "kind": "distributed", "module": name, "span": span,
                        "force": (rng.normal(size=3) * 0.3 * force / length).tolist(),
                        "moment": (rng.normal(size=3) * 0.05 * force).tolist(),
                        "frame": str(rng.choice(["global", "body"]))})
    return out


def random_muscle_robot(seed):
    """:func:`random_robot` with every TCA replaced by another muscle, sized to its module: a
    thin (25 micrometre) SMA wire at 25-72 degC or a small McKibben muscle at 0-20 kPa (some
    ``tension_only``)."""
    rng = np.random.default_rng(seed + 10_000)
    scenario = random_robot(seed)
    scenario["muscle_types"] = {"wire": {"kind": "sma", "wire_diameter": "25 um"},
                                "pam": {"kind": "mckibben", "radius": "0.3 mm", "braid_angle": "22 deg",
                                        "correction": float(rng.uniform(1.0, 1.3)), "max_pressure": "30 kPa"}}
    for module in scenario["modules"]:
        for k, actuator in enumerate(module["actuators"]):
            if actuator["kind"] != "tca":
                continue
            common = {"name": actuator["name"], "route": actuator["route"], "tension_only": bool(rng.random() < 0.3)}
            if rng.random() < 0.5:
                module["actuators"][k] = dict(common, kind="sma", type="wire", temperature=float(rng.uniform(25, 72)))
            else:
                module["actuators"][k] = dict(common, kind="mckibben", type="pam", pressure=float(rng.uniform(0, 20e3)))
    return scenario


def random_tendon_robot(seed):
    """A random robot of the kind that exposed the curve-knot defect (issue 34, item 8): one or
    two modules, each with full-length tendons (prescribed tension, or displacement-controlled
    with a stiffness or a compliance, some ``tension_only`` and pushed slack) on straight,
    helical and spline routes with several knots, TCAs over partial spans inside them, and point
    masses inside the spans: strain jumps where actuators run through."""
    rng = np.random.default_rng(seed + 20_000)
    count = int(rng.integers(1, 3))
    modules, loads = [], []
    for k in range(count):
        length = float(rng.uniform(0.03, 0.08))
        diameter = float(rng.uniform(0.006, 0.012))
        stiffness = 0.5e6 * math.pi * diameter**4 / 64
        force = stiffness / length**2
        config = {"name": f"m{k}", "length": length, "material": "soft",
                  "cross_section": {"shape": "circle", "diameter": diameter}, "actuators": []}
        if k > 0:
            config["connector"] = {"offset": (rng.uniform(-1, 1, 3) * 0.002).tolist(), "mass": float(rng.uniform(0, 0.002))}
        for a in range(int(rng.integers(1, 3))):
            config["actuators"].append(_full_length_tendon(rng, f"t{a}", length, diameter, force))
        span = sorted(rng.uniform(0.1, 0.9, 2) * length)
        if span[1] - span[0] > 0.2 * length:
            config["actuators"].append({"name": "tca", "kind": "tca", "type": "nylon", "temperature": float(rng.uniform(25, 90)),
                                        "route": {"kind": "straight", "radius": float(rng.uniform(0.15, 0.35) * diameter),
                                                  "angle": float(rng.uniform(0, 2 * math.pi)), "span": [float(v) for v in span]}})
        for j in range(int(rng.integers(1, 3))):
            loads.append({"name": f"m{k}_mass{j}", "kind": "mass", "module": f"m{k}",
                          "at": float(rng.uniform(0.05, 0.95) * length), "mass": float(rng.uniform(0.02, 0.2) * force / 9.81)})
        modules.append(config)
    direction = rng.normal(size=3)
    return {"name": f"tendons_{seed}",
            "gravity": (rng.uniform(0, 9.81) * direction / np.linalg.norm(direction)).tolist(),
            "base": {"position": [0, 0, 0], "orientation": {"axis": rng.normal(size=3).tolist(),
                                                            "angle": float(rng.uniform(0, math.pi))}},
            "materials": {"soft": {"youngs_modulus": float(rng.uniform(0.2e6, 1e6)), "poisson_ratio": 0.5,
                                   "density": float(rng.uniform(1000, 1500))}},
            "tca_types": {"nylon": TCA_TYPE}, "modules": modules, "loads": loads}


def _full_length_tendon(rng, name, length, diameter, force):
    """A tendon along the whole module on a random route, driven by tension or displacement."""
    radius = float(rng.uniform(0.1, 0.35) * diameter)
    kind = rng.choice(["straight", "helix", "curve"], p=[0.3, 0.3, 0.4])
    if kind != "curve":
        route = _placed_route(rng, kind, radius)
    else:
        knots = int(rng.integers(4, 7))           # knots at least L / (2 knots) apart
        gaps = rng.uniform(1, 2, knots - 1)
        s = np.r_[0.0, np.cumsum(gaps)] / gaps.sum() * length
        xy = rng.uniform(-1, 1, (knots, 2)) * 0.7 * radius / math.sqrt(2)     # room for the spline's swing
        route = {"kind": "curve", "points": np.column_stack([s, xy]).tolist()}
    tendon = {"name": name, "kind": "tendon", "route": route}
    if rng.random() < 0.4:
        return dict(tendon, tension=float(rng.uniform(0.05, 0.3) * force * length / max(radius, 1e-3)))
    tendon.update(control="displacement", tension_only=bool(rng.random() < 0.7),
                  displacement=float(rng.uniform(-0.02, 0.01) * length))
    stiffness = float(rng.uniform(10, 1000))
    return dict(tendon, **({"stiffness": stiffness} if rng.random() < 0.5 else {"compliance": 1 / stiffness}))


def ramped_dynamics(seed, integrator, obstacles=(), gravity=1.0, fraction=0.2, contact=None):
    """``(TimeSimulation, TimeSeries)`` of rod dynamics on :func:`random_robot` ``seed`` (no
    distributed loads: the energy account counts point loads' work), its actuators ramped over
    the first 2 of 8 of its shortest time scales (TCAs 15 degC hotter, tendons pulled 30 %
    harder) in steps of ``fraction`` of it (0.2: 40 steps), every step's global balance checked;
    with ``obstacles`` (scenario entries) and ``contact`` (the scenario's ``contact`` settings);
    ``gravity`` scales gravity over the same ramp (a lift's acceleration)."""
    from tca_casadi import Simulation
    from tca_casadi.discretisation.dynamics import time_scale
    from tca_casadi.time_simulation.timeline import TimeSimulation
    scenario = random_robot(seed)
    scenario["loads"] = [load for load in scenario["loads"] if load["kind"] != "distributed"]
    changes = {}
    for module in scenario["modules"]:
        for actuator in module["actuators"]:
            key = f"{module['name']}.{actuator['name']}"
            if actuator["kind"] == "tca":
                changes[f"{key}.temperature"] = actuator["temperature"] + 15.0
            else:
                changes[f"{key}.tension"] = 1.3 * actuator["tension"]
    if gravity != 1.0:
        changes["gravity"] = [float(gravity * g) for g in Simulation.from_file(scenario).scenario.gravity]
    shortest = min(time_scale(m) for m in Simulation.from_file(scenario).robot.modules)
    step = fraction * shortest
    scenario.update(dynamics={"enabled": True, "integrator": integrator, "balance_every": 1},
                    duration=round(8 / fraction) * step, timeline=[{"at": 0.0, "set": changes, "ramp": 2 * shortest}],
                    obstacles=list(obstacles))
    if contact is not None:
        scenario["contact"] = dict(scenario.get("contact") or {}, **contact)
    timed = TimeSimulation(Simulation.from_file(scenario), dt=step)
    return timed, timed.run()
