"""Writing results the pipeline does not make yet (cages, composed mesh) from a hand-made
result dict in the module's format: no native module needed."""

import bpy
import numpy as np
import pytest

from conftest import mesh_object
from genbrep import bridge, report, results


def _cube_cage():
    vertices = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    quads = np.array([(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
                      (1, 5, 7, 3)], np.int32)
    return vertices, quads


def _result():
    vertices, quads = _cube_cage()
    triangles = np.array([(0, 1, 2), (0, 2, 3), (0, 3, 1), (1, 3, 2)], np.int32)
    tetra = np.array([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], float)
    return {
        "report": {"stages": {"mesh": 0.1, "compose": 0.2}, "diagnostics": ["a warning"]},
        "design": {"vertices": tetra, "faces": triangles,
                   "face_source": np.arange(4, dtype=np.int32)},
        "partition": {"face_solid": np.array([0, -1, -1, 1], np.int32),
                      "face_component": np.array([-1, 0, 0, -1], np.int32),
                      "loops": [{"vertices": np.array([0, 1, 2], np.int32), "solids": [0]}]},
        "cages": [{"name": "arm", "component": 0, "vertices": vertices, "faces": quads,
                   "crease_edges": np.array([[0, 1], [3, 1], [0, 7]], np.int32),
                   "crease_values": np.array([1.0, 0.5, 1.0], np.float32),
                   "subdivision": {"boundary_smooth": "PRESERVE_CORNERS",
                                   "use_limit_surface": True, "quality": 4, "levels": 3}}],
        "composed": {"vertices": tetra, "faces": triangles,
                     "face_source": np.arange(4, dtype=np.int32)},
    }


def _edge_creases(mesh):
    values = np.empty(len(mesh.edges), np.float32)
    if "crease" in bpy.types.MeshEdge.bl_rna.properties:
        mesh.edges.foreach_get("crease", values)
    else:
        mesh.attributes["crease_edge"].data.foreach_get("value", values)
    edges = np.empty(len(mesh.edges) * 2, np.int32)
    mesh.edges.foreach_get("vertices", edges)
    return {tuple(sorted(e)): v for e, v in zip(edges.reshape(-1, 2).tolist(), values) if v}


def test_cages_and_composed_are_written(empty_scene):
    collection = bridge.write_results(empty_scene, "part", ["keep_in", "keep_out"], _result(),
                                      report.to_json({}))
    objects = {o.name: o for o in collection.objects}
    assert set(objects) == {"part partition", "part boundary loops", "part cage arm",
                            "part control net arm", "part composed"}
    cage = objects["part cage arm"]
    assert len(cage.data.polygons) == 6 and all(p.loop_total == 4 for p in cage.data.polygons)
    modifier = cage.modifiers["genbrep Subdivision"]
    assert (modifier.type, modifier.subdivision_type) == ("SUBSURF", "CATMULL_CLARK")
    assert (modifier.levels, modifier.quality) == (3, 4)
    assert modifier.use_limit_surface and modifier.use_creases
    assert modifier.boundary_smooth == "PRESERVE_CORNERS"
    # (0, 7) is not a cage edge and is ignored
    assert _edge_creases(cage.data) == {(0, 1): pytest.approx(1.0), (1, 3): pytest.approx(0.5)}
    assert cage["genbrep_component"] == 0
    assert objects["part partition"].hide_render and not objects["part composed"].hide_render
    assert len(objects["part boundary loops"].data.edges) == 3
    assert bridge.cage_objects(collection) == [cage]


def test_cage_shows_its_limit_surface_under_its_control_net(empty_scene):
    collection = bridge.write_results(empty_scene, "part", ["keep_in", "keep_out"], _result(),
                                      "{}")
    cage = collection.objects["part cage arm"]
    net = collection.objects["part control net arm"]
    assert cage.display_type == "TEXTURED" and not cage.hide_get()  # shaded limit surface
    assert net.data == cage.data and not net.modifiers  # the control net itself
    assert net.display_type == "WIRE" and net.parent == cage
    assert net.hide_select and net.hide_render and not net.hide_get()
    assert "genbrep_component" not in net
    assert not collection.objects["part composed"].hide_get()
    # A recompose gives the cage a new mesh: the net draws the new one, the old is freed.
    old = cage.data.name
    vertices, quads = _cube_cage()
    bridge.replace_mesh_data(cage, vertices * 1.1, quads)
    assert net.data == cage.data and old not in bpy.data.meshes


def test_rewrite_replaces_objects(empty_scene):
    for _ in range(2):
        bridge.write_results(empty_scene, "part", ["keep_in", "keep_out"], _result(), "{}")
    assert len(bpy.data.collections["genbrep part"].objects) == 5  # the net shares a mesh
    assert len(bpy.data.meshes) == 4
    assert bridge.remove_results("part")
    assert "genbrep part" not in bpy.data.collections and len(bpy.data.meshes) == 0


def test_partition_only_result_is_written(empty_scene):
    result = _result()
    result.update(cages=[], composed=None)
    collection = bridge.write_results(empty_scene, "part", ["keep_in", "keep_out"], result, "{}")
    partition = collection.objects["part partition"]
    assert not partition.hide_render
    colours = np.empty(len(partition.data.loops) * 4, np.float32)
    partition.data.color_attributes[results.PARTITION_COLOR_ATTRIBUTE].data.foreach_get(
        "color", colours)
    per_face = colours.reshape(-1, 3, 4)[:, 0]
    assert not np.allclose(per_face[0], per_face[3])  # two different solids
    np.testing.assert_allclose(per_face[1], per_face[2])  # the same organic component


def _face_materials(obj):
    index = np.empty(len(obj.data.polygons), np.int32)
    obj.data.polygons.foreach_get("material_index", index)
    return [obj.data.materials[i] for i in index]


def test_partition_and_cage_colours_are_material_colours(empty_scene):
    collection = bridge.write_results(empty_scene, "part", ["keep_in", "keep_out"], _result(),
                                      "{}")
    partition = collection.objects["part partition"].data
    colours = np.empty(len(partition.loops) * 4, np.float32)
    partition.color_attributes[results.PARTITION_COLOR_ATTRIBUTE].data.foreach_get(
        "color", colours)
    # Each face's material has the face's partition colour as its viewport colour.
    materials = _face_materials(collection.objects["part partition"])
    assert [m.name for m in materials] == ["genbrep keep-in 0", "genbrep component 0",
                                           "genbrep component 0", "genbrep keep-out 1"]
    for material, colour in zip(materials, colours.reshape(-1, 3, 4)[:, 0]):
        np.testing.assert_allclose(material.diffuse_color, colour, rtol=1e-6)
    default = bpy.data.materials.new("default").diffuse_color
    assert not any(np.allclose(m.diffuse_color, default) for m in materials)
    # The cage of component 0 uses the material of its region in the partition; the
    # composed solid's faces that of their source (solids 0, 1, then unknown solids 2, 3).
    assert collection.objects["part cage arm"].data.materials[0] == materials[1]
    composed = _face_materials(collection.objects["part composed"])
    assert composed[:2] == [materials[0], materials[3]]
    assert [m.name for m in composed[2:]] == ["genbrep organic"] * 2


def test_composed_result_hides_the_inputs_until_shown(empty_scene):
    triangle = ([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 2)])
    inputs = [mesh_object(name, *triangle, role) for name, role in
              (("part", "DESIGN"), ("lug", "KEEP_IN"), ("hole", "KEEP_OUT"))]
    bystander = mesh_object("lamp", *triangle, "NONE")
    result = _result()
    result.update(composed=None)
    bridge.write_results(empty_scene, "part", ["keep_in", "keep_out"], result, "{}")
    assert not any(o.hide_get() for o in inputs)  # nothing composed: as they were
    bridge.write_results(empty_scene, "part", ["keep_in", "keep_out"], _result(), "{}")
    settings = empty_scene.genbrep_settings
    assert not settings.show_inputs
    assert all(o.hide_get() for o in inputs) and not bystander.hide_get()
    assert not any(o.hide_render or o.hide_viewport for o in inputs)  # the viewport only
    settings.show_inputs = True
    assert not any(o.hide_get() for o in inputs)
    settings.show_inputs = False
    assert all(o.hide_get() for o in inputs) and not bystander.hide_get()
    assert set(empty_scene.objects) >= {*inputs, bystander}  # none deleted
    assert bpy.ops.genbrep.clear_results(design="part") == {"FINISHED"}
    assert settings.show_inputs and not any(o.hide_get() for o in inputs)


def test_solid_views_colour_by_material(empty_scene):
    views = [s for screen in bpy.data.screens for a in screen.areas for s in a.spaces
             if s.type == "VIEW_3D"]
    assert len(views) >= 2
    views[0].shading.type, views[0].shading.color_type = "SOLID", "OBJECT"
    views[1].shading.type, views[1].shading.color_type = "WIREFRAME", "OBJECT"
    bridge.show_material_colours(bpy.data.screens)
    assert views[0].shading.color_type == "MATERIAL"
    assert (views[1].shading.type, views[1].shading.color_type) == ("WIREFRAME", "OBJECT")


def _members(obj, name):
    group = obj.vertex_groups[name].index
    return {v.index: round(e.weight, 3) for v in obj.data.vertices for e in v.groups
            if e.group == group}


def test_irregular_vertices_off_singularities_are_a_vertex_group_kept_through_recompose(
        empty_scene):
    result = _result()
    result["cages"].append(dict(result["cages"][0], name="leg", component=1,
                                irregular_off_singularities=np.array([0, 7], np.int32)))
    collection = bridge.write_results(empty_scene, "part", ["keep_in", "keep_out"], result, "{}")
    arm, leg = collection.objects["part cage arm"], collection.objects["part cage leg"]
    # No group on a cage without such vertices; on the other, exactly the listed ones.
    assert results.OFF_SINGULARITIES_GROUP not in arm.vertex_groups
    assert _members(leg, results.OFF_SINGULARITIES_GROUP) == {0: 1.0, 7: 1.0}
    # A group of the user's own, and the pulled cage of a recompose: moved vertices and an
    # appended one (the pull keeps the cage's vertices first). Both groups keep their members.
    mine = leg.vertex_groups.new(name="mine")
    mine.add([3], 0.5, "REPLACE")
    vertices, quads = _cube_cage()
    pulled = np.vstack([vertices * 1.1, [[0, 0, 2]]])
    mesh = bridge.replace_mesh_data(leg, pulled, quads)
    assert leg.data == mesh and len(mesh.vertices) == 9
    assert _members(leg, results.OFF_SINGULARITIES_GROUP) == {0: 1.0, 7: 1.0}
    assert _members(leg, "mine") == {3: 0.5}
