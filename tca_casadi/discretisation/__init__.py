"""Discretisation: collocation scheme, meshes with breakpoints, NLP assembly."""
from .collocation import CollocationNLP
from .mesh import CollocationScheme, ModuleMesh, build_mesh

__all__ = ["CollocationNLP", "CollocationScheme", "ModuleMesh", "build_mesh"]
