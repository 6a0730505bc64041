"""VTK files of solutions, for ParaView and other VTK tools (``--vtk`` on ``solve``, ``sequence``
and ``simulate``), written through meshio; SI units throughout.

Each frame (a solution) is up to three unstructured grids (``.vtu``):

* ``STEM_rods.vtu``: every module's centerline nodes as points joined by line cells, with point
  data ``arc_length_m``, ``module`` (index), the body frame ``d1``, ``d2``, ``d3`` (the
  columns of R), the body-frame strains ``curvature_per_m`` (u) and ``strain`` (v), and the
  global internal ``force_N`` and ``moment_Nm``;
* ``STEM_actuators.vtu``: every actuator's path as lines, with cell data ``actuator`` (index),
  ``tension_N`` and ``temperature_degC`` (NaN where an actuator has none);
* ``STEM_surfaces.vtu`` (when there are any): obstacles and objects as quadrilaterals, with cell
  data ``surface`` (index); unbounded shapes (planes, cylinders) cut to a box around the rods.

A ``.pvd`` collection lists the frames with their times (``timestep``) and parts, so that
ParaView opens a whole run as a time series, and ``NAME_names.json`` says what the indices
``module``, ``actuator`` and ``surface`` name (VTK's unstructured grids carry no strings).
"""
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np

from .output import atomic_path

#: quadrilaterals around a sphere or cylinder, and along a cylinder
AROUND, ALONG = 24, 12


def rod_mesh(solution):
    """The rods of ``solution`` as a meshio Mesh (module docstring)."""
    import meshio
    points, lines, data, start = [], [], {name: [] for name in
                                          ("arc_length_m", "module", "d1", "d2", "d3", "curvature_per_m", "strain",
                                           "force_N", "moment_Nm")}, 0
    for m, module in enumerate(solution.modules):
        n = module.p.shape[1]
        points.append(module.p.T)
        lines.append(np.column_stack([np.arange(start, start + n - 1), np.arange(start + 1, start + n)]))
        data["arc_length_m"].append(module.s)
        data["module"].append(np.full(n, m, dtype=np.int32))
        for k in range(3):
            data[f"d{k + 1}"].append(module.R[:, k, :].T)
        data["curvature_per_m"].append(module.u.T)
        data["strain"].append(module.v.T)
        data["force_N"].append(module.force.T)
        data["moment_Nm"].append(module.moment.T)
        start += n
    return meshio.Mesh(np.vstack(points), [("line", np.vstack(lines))],
                       point_data={name: np.concatenate(parts) for name, parts in data.items()})


def actuator_mesh(solution):
    """The actuators of ``solution`` as a meshio Mesh (module docstring), or None without any."""
    import meshio
    if not solution.actuators:
        return None
    points, lines, index, tension, temperature, start = [], [], [], [], [], 0
    for k, actuator in enumerate(solution.actuators.values()):
        path = np.asarray(actuator.path, float)
        n = path.shape[1]
        points.append(path.T)
        lines.append(np.column_stack([np.arange(start, start + n - 1), np.arange(start + 1, start + n)]))
        index.append(np.full(n - 1, k, dtype=np.int32))
        tension.append(np.full(n - 1, actuator.tension, float))
        temperature.append(np.full(n - 1, np.nan if actuator.temperature is None else actuator.temperature, float))
        start += n
    return meshio.Mesh(np.vstack(points), [("line", np.vstack(lines))],
                       cell_data={"actuator": [np.concatenate(index)], "tension_N": [np.concatenate(tension)],
                                  "temperature_degC": [np.concatenate(temperature)]})


def surface_mesh(solution, objects=()):
    """The obstacles of ``solution`` and the ``objects`` (poses with ``corners()``) as a meshio
    Mesh of quadrilaterals, or None without any."""
    import meshio
    extent = np.hstack([module.p for module in solution.modules])
    low, high = extent.min(axis=1), extent.max(axis=1)
    centre, half = (low + high) / 2, max(float(np.max(high - low)) / 2, 1e-3) * 1.2
    parts = [(shape.name, _shape_quads(shape, centre, half)) for shape in solution.obstacles]
    parts += [(name, _box_quads(pose.corners())) for name, pose in _named(objects)]
    if not parts:
        return None
    points, quads, index, start = [], [], [], 0
    for k, (_, (vertices, faces)) in enumerate(parts):
        points.append(vertices)
        quads.append(faces + start)
        index.append(np.full(len(faces), k, dtype=np.int32))
        start += len(vertices)
    return meshio.Mesh(np.vstack(points), [("quad", np.vstack(quads))], cell_data={"surface": [np.concatenate(index)]})


def surface_names(solution, objects=()):
    """The names of the surfaces :func:`surface_mesh` writes, in its index order."""
    return [shape.name for shape in solution.obstacles] + [name for name, _ in _named(objects)]


def _named(objects):
    """``[(name, pose)]`` of a ``{name: pose}`` mapping or a list of poses (named by position)."""
    if isinstance(objects, dict):
        return list(objects.items())
    return [(getattr(pose, "name", f"object{k}"), pose) for k, pose in enumerate(objects)]


def _grid_quads(vertices):
    """``(points (n m, 3), quads)`` of a grid of vertices (3, n, m), its cells as quadrilaterals."""
    _, n, m = vertices.shape
    ids = np.arange(n * m).reshape(n, m)
    faces = np.column_stack([ids[:-1, :-1].ravel(), ids[1:, :-1].ravel(), ids[1:, 1:].ravel(), ids[:-1, 1:].ravel()])
    return vertices.reshape(3, -1).T, faces


def _box_quads(corners):
    """The 6 faces of a box from its 8 corners (3, 8), corner k at signs ``(k >> 2, k >> 1, k) & 1``."""
    faces = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])
    return np.asarray(corners, float).T, faces


def _shape_quads(shape, centre, half):
    """``(points, quads)`` of an obstacle (module docstring); ``centre``, ``half`` [m]: the box
    around the rods that unbounded shapes are cut to."""
    kind = type(shape).__name__
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, AROUND + 1), np.linspace(-1, 1, ALONG + 1), indexing="ij")
    position = np.asarray(shape.position, float)
    if kind == "Sphere":
        r = float(shape.radius)
        latitude = v * np.pi / 2
        grid = np.stack([r * np.cos(u) * np.cos(latitude), r * np.sin(u) * np.cos(latitude), r * np.sin(latitude)])
        return _grid_quads(grid + position[:, None, None])
    if kind == "Cylinder":
        r, axes = float(shape.radius), np.asarray(shape.rotation, float)
        along = (centre - position) @ axes[:, 2]
        local = np.stack([r * np.cos(u), r * np.sin(u), along + half * v])
        return _grid_quads(np.einsum("ij,jkl->ikl", axes, local) + position[:, None, None])
    if kind == "Plane":
        n = np.asarray(shape.normal, float) / np.linalg.norm(shape.normal)
        a = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        foot = centre - ((centre - position) @ n) * n
        grid = np.linspace(-half, half, 9)
        plane = foot[:, None, None] + a[:, None, None] * grid[None, :, None] + b[:, None, None] * grid[None, None, :]
        return _grid_quads(plane)
    signs = np.array([[(k >> 2) & 1, (k >> 1) & 1, k & 1] for k in range(8)], float) * 2 - 1     # Box
    corners = position[:, None] + np.asarray(shape.rotation, float) @ (signs * np.asarray(shape.size, float) / 2).T
    return _box_quads(corners)


def write_frame(solution, directory, stem, objects=()):
    """Write ``solution``'s grids as ``STEM_rods.vtu``, ``STEM_actuators.vtu`` and
    ``STEM_surfaces.vtu`` (those that are not empty) into ``directory``, each atomically;
    returns the paths written."""
    import meshio
    directory = Path(directory)
    written = []
    for part, mesh in (("rods", rod_mesh(solution)), ("actuators", actuator_mesh(solution)),
                       ("surfaces", surface_mesh(solution, objects))):
        if mesh is None:
            continue
        path = directory / f"{stem}_{part}.vtu"
        with atomic_path(path) as temporary:
            meshio.write(temporary, mesh, file_format="vtu")
        written.append(path)
    return written


def write_series(frames, directory, name, prefix="vtk"):
    """Write every frame ``(t [s], solution, objects)`` of ``frames`` (:func:`write_frame`, stems
    ``PREFIX_0000`` ...), ``NAME_names.json`` (the names behind the index arrays, from the first
    frame) and the collection ``NAME.pvd`` that lists the frames with their times, one part per
    kind of grid; returns the paths written (the collection last)."""
    directory = Path(directory)
    frames = list(frames)
    digits = max(4, len(str(len(frames) - 1)))
    collection = ElementTree.Element("VTKFile", type="Collection", version="0.1")
    datasets = ElementTree.SubElement(collection, "Collection")
    written, parts = [], {}
    for k, (t, solution, objects) in enumerate(frames):
        for path in write_frame(solution, directory, f"{prefix}_{k:0{digits}d}", objects):
            part = parts.setdefault(path.stem.rsplit("_", 1)[1], len(parts))
            ElementTree.SubElement(datasets, "DataSet", timestep=repr(float(t)), group="", part=str(part),
                                   file=path.name)
            written.append(path)
    from .output import write_json
    if frames:
        _, first, objects = frames[0]
        written.append(write_json(directory / f"{name}_names.json", {
            "module": [m.name for m in first.modules], "actuator": list(first.actuators),
            "surface": surface_names(first, objects)}))
    index = directory / f"{name}.pvd"
    with atomic_path(index) as temporary:
        ElementTree.ElementTree(collection).write(temporary, encoding="utf-8", xml_declaration=True)
    return written + [index]


def read_collection(path):
    """``[(t [s], part, file)]`` of a ``.pvd`` collection (the files relative to its folder)."""
    root = ElementTree.parse(path).getroot()
    return [(float(d.get("timestep")), int(d.get("part")), Path(path).parent / d.get("file"))
            for d in root.iter("DataSet")]
