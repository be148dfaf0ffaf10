"""Blender's Subdivision Surface modifier shows the limit surface the fitter uses.

A cage is written the way the add-on writes cages (bridge.new_mesh, edge creases, the
modifier from results.subdivision_settings: use_limit_surface on, quality, boundary_smooth,
use_creases), the evaluated mesh is read through the depsgraph, and its vertices are
compared with genbrep_native.limit_points at the same density (level L = 2^L samples per
quad edge): every evaluated vertex must lie on a native sample and every native sample on
an evaluated vertex, within 1e-5 of the cage size. Blender stores float32, so the two agree
to about 3e-7; 1e-5 is tight enough to tell Blender's crease mapping (sharpness 10·c²) from
a linear one (they differ by 3e-4 of the size on the creased patch below)."""

import bpy
import numpy as np
import pytest
from mathutils.kdtree import KDTree

from conftest import needs_native
from genbrep import bridge, native

pytestmark = needs_native

LEVEL = 5
TOLERANCE = 1e-5  # of the cage's bounding-box diagonal


@pytest.fixture
def limit_points():
    module = native.load()
    if not hasattr(module, "limit_points"):
        pytest.skip("genbrep_native has no limit_points: bind_fit is not wired into module.cpp")
    return module.limit_points


def _grid_cage(nx=5, ny=4):
    """A non-planar (nx+1)×(ny+1) grid patch: quads CCW from +z, one open boundary."""
    i, j = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1))
    vertices = np.stack([i + 0.2 * np.sin(j), j + 0.15 * np.cos(1.7 * i),
                         0.6 * np.sin(0.9 * i) * np.cos(1.3 * j)], axis=-1).reshape(-1, 3)
    quads = [(y * (nx + 1) + x, y * (nx + 1) + x + 1, (y + 1) * (nx + 1) + x + 1,
              (y + 1) * (nx + 1) + x) for y in range(ny) for x in range(nx)]
    return vertices, np.array(quads, np.int32)


def _cube_cage():
    """A closed cage whose eight vertices are all extraordinary (valence 3)."""
    vertices = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    vertices *= [1.0, 0.8, 1.3]
    quads = np.array([(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
                      (1, 5, 7, 3)], np.int32)
    return vertices, quads


def _evaluated_vertices(vertices, quads, boundary_smooth, quality, creases):
    mesh = bridge.new_mesh("limit cage", vertices, quads)
    if creases is not None:
        bridge.set_edge_creases(mesh, creases[0], creases[1])
    obj = bpy.data.objects.new("limit cage", mesh)
    bpy.context.scene.collection.objects.link(obj)
    bridge.add_subdivision(obj, {"boundary_smooth": boundary_smooth, "use_limit_surface": True,
                                 "quality": quality, "levels": LEVEL})
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    result = evaluated.to_mesh()
    co = np.empty(len(result.vertices) * 3, np.float32)
    result.vertices.foreach_get("co", co)
    evaluated.to_mesh_clear()
    return co.reshape(-1, 3).astype(float)


def _farthest_nearest(points, targets):
    """max over points of the distance to the nearest target."""
    tree = KDTree(len(targets))
    for index, target in enumerate(targets):
        tree.insert(target, index)
    tree.balance()
    return max(tree.find(p)[2] for p in points)


def _compare(limit_points, vertices, quads, boundary_smooth="ALL", quality=3, creases=None):
    # The native side sees exactly the float32 positions Blender stores.
    vertices = np.asarray(vertices, np.float32).astype(float)
    blender = _evaluated_vertices(vertices, quads, boundary_smooth, quality, creases)
    kwargs = {}
    if creases is not None:
        kwargs = {"crease_edges": np.asarray(creases[0], np.int32),
                  "crease_values": np.asarray(creases[1], np.float32)}
    ours, faces = limit_points(vertices, quads, 2 ** LEVEL, boundary_smooth=boundary_smooth,
                               quality=quality, **kwargs)
    assert ours.dtype == np.float64 and ours.shape[1] == 3
    assert faces.dtype == np.int32 and faces.shape == (len(quads) * 2 * 4 ** LEVEL, 3)
    assert len(blender) == len(ours)  # the same grid: V + E(n-1) + F(n-1)²
    size = np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0))
    blender_to_ours = _farthest_nearest(blender, ours)
    ours_to_blender = _farthest_nearest(ours, blender)
    print(f"limit surface, {len(quads)} quads, {boundary_smooth}, quality {quality}, "
          f"creases {0 if creases is None else len(creases[1])}: Blender→native "
          f"{blender_to_ours / size:.2e}, native→Blender {ours_to_blender / size:.2e} of the size")
    assert blender_to_ours <= TOLERANCE * size
    assert ours_to_blender <= TOLERANCE * size


def test_open_patch_matches_blender(empty_scene, limit_points):
    vertices, quads = _grid_cage()
    _compare(limit_points, vertices, quads)


def test_creased_patch_matches_blender(empty_scene, limit_points):
    # Interior creases 0.5 (sharpness 2.5) and 1.0 (infinitely sharp), and a creased
    # boundary pair meeting at a corner (Blender then sharpens that valence-2 corner).
    vertices, quads = _grid_cage()
    creases = ([(7, 8), (8, 9), (14, 20), (0, 1), (0, 6)], [0.5, 0.5, 1.0, 0.8, 0.8])
    _compare(limit_points, vertices, quads, creases=creases)


def test_preserve_corners_matches_blender(empty_scene, limit_points):
    vertices, quads = _grid_cage()
    _compare(limit_points, vertices, quads, boundary_smooth="PRESERVE_CORNERS", quality=4)


def test_closed_cage_with_extraordinary_vertices_matches_blender(empty_scene, limit_points):
    vertices, quads = _cube_cage()
    _compare(limit_points, vertices, quads)


def test_limit_points_rejects_bad_input(limit_points):
    vertices, quads = _grid_cage()
    with pytest.raises(native.load().ConversionError, match="boundary_smooth"):
        limit_points(vertices, quads, 4, boundary_smooth="NONE")
    bad = quads.copy()
    bad[0, 1] = 1000
    with pytest.raises(native.load().ConversionError, match="vertex"):
        limit_points(vertices, bad, 4)
