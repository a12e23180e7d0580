"""Predicates of queries, combined with &, | and ~."""

from typing import Callable, Union

from . import Aabb, Capsule, Frustum, Node, OrientedBox, Predicate, Segment, Sphere

def any() -> Predicate:
    """Every node."""

def occupied() -> Predicate:
    """Nodes holding an occupied voxel (value above the occupied threshold)."""

def free() -> Predicate:
    """Nodes whose voxels are all free."""

def unknown() -> Predicate:
    """Nodes neither occupied nor free."""

def contains_occupied() -> Predicate:
    """Nodes with an occupied voxel (as occupied)."""

def contains_free() -> Predicate:
    """Nodes with a free voxel."""

def contains_unknown() -> Predicate:
    """Nodes with an unknown voxel."""

def leaf() -> Predicate:
    """Nodes without children at the query's depth; together they tile the map once."""

def depth(depth: int) -> Predicate:
    """Nodes at exactly this depth."""

def min_depth(depth: int) -> Predicate:
    """Nodes at this depth or coarser."""

def max_depth(depth: int) -> Predicate:
    """Nodes at this depth or finer."""

def intersects(shape: Union[Aabb, Sphere, OrientedBox, Capsule, Segment, Frustum]) -> Predicate:
    """Nodes that meet the shape (an Aabb, Sphere, OrientedBox, Capsule, Segment or Frustum; see the shapes)."""

def satisfies(rule: Callable[[Node], bool]) -> Predicate:
    """Nodes for which rule(node) is true (node: a umbra.Node). Called per node the rest of an & admits; combine it with other predicates to keep a query fast."""
