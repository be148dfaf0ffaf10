"""bpy <-> numpy: read input meshes, write the results of a conversion.

Arrays move with foreach_get / foreach_set only. Version differences handled here:
MeshPolygon.loop_total (read-only from 4.2), edge creases (MeshEdge.crease in 3.x, the
'crease_edge' attribute from 4.0), smooth shading (Mesh.shade_smooth from 4.1).
"""

import bpy
import numpy as np

from . import checks, options, props, results

_LOOP_TOTAL_WRITABLE = not bpy.types.MeshPolygon.bl_rna.properties["loop_total"].is_readonly
_EDGE_CREASE_PROPERTY = "crease" in bpy.types.MeshEdge.bl_rna.properties

# reading --------------------------------------------------------------------------------

def read_triangles(obj, depsgraph):
    """World-space vertices (N×3 float64) and triangles (M×3 int32) of obj, modifiers applied."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        if mesh is None:
            return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32)
        mesh.calc_loop_triangles()
        co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        triangles = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
        mesh.loop_triangles.foreach_get("vertices", triangles)
    finally:
        evaluated.to_mesh_clear()
    matrix = np.array(evaluated.matrix_world, dtype=np.float64)
    vertices = co.reshape(-1, 3).astype(np.float64) @ matrix[:3, :3].T + matrix[:3, 3]
    triangles = triangles.reshape(-1, 3)
    if np.linalg.det(matrix[:3, :3]) < 0.0:  # mirrored: keep outward orientation
        triangles = triangles[:, [0, 2, 1]]
    return vertices, np.ascontiguousarray(triangles)


def design_grid(obj):
    """(origin, h) of the voxel grid recorded on a design object, or None."""
    recorded = {key: obj.get(key) for key in (options.GRID_H_PROPERTY,
                                              options.GRID_ORIGIN_PROPERTY)
                if obj.get(key) is not None}
    return options.grid_from_properties(recorded)


def gather_input(scene, depsgraph, design_obj):
    """(design, solids) as dicts of name, role identifier, vertices, faces (world space).

    Solids are every object of the scene with a solid role, sorted by name, so solid indices
    in the result are stable run after run.
    """
    vertices, faces = read_triangles(design_obj, depsgraph)
    design = dict(name=design_obj.name, vertices=vertices, faces=faces)
    solids = []
    for role in ("KEEP_IN", "KEEP_OUT", "SEED"):
        for obj in props.objects_with_role(scene, role):
            vertices, faces = read_triangles(obj, depsgraph)
            solids.append(dict(name=obj.name, role=role, vertices=vertices, faces=faces))
    solids.sort(key=lambda s: s["name"])
    return design, solids


def read_cage(obj):
    """The edited control cage of a cage object (its own mesh, not the subdivided one),
    in world space, as the dict recompose() takes; raises checks.InputError."""
    mesh = obj.data
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float64)
    mesh.vertices.foreach_get("co", co)
    matrix = np.array(obj.matrix_world, dtype=np.float64)
    vertices = co.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    sizes = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    corners = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    edges = np.empty(len(mesh.edges) * 2, dtype=np.int32)
    mesh.edges.foreach_get("vertices", edges)
    crease = np.zeros(len(mesh.edges), dtype=np.float32)
    if _EDGE_CREASE_PROPERTY:
        mesh.edges.foreach_get("crease", crease)
    elif mesh.attributes.get("crease_edge") is not None:
        mesh.attributes["crease_edge"].data.foreach_get("value", crease)
    if np.linalg.det(matrix[:3, :3]) < 0.0:  # mirrored: keep the quads' outward orientation
        corners = _reverse_polygons(corners, sizes)
    return checks.cage_input(obj.name, vertices, sizes, corners, edges.reshape(-1, 2), crease)


def _reverse_polygons(corners, sizes):
    out, start = corners.copy(), 0
    for size in sizes:
        out[start:start + size] = corners[start:start + size][::-1]
        start += size
    return out


def group_weights(obj):
    """Per vertex group of obj, by name: {vertex index: weight} of the vertices in it."""
    names = {group.index: group.name for group in obj.vertex_groups}
    weights = {name: {} for name in names.values()}
    for vertex in obj.data.vertices:
        for element in vertex.groups:
            if element.group in names:
                weights[names[element.group]][vertex.index] = element.weight
    return weights


def set_group_weights(obj, weights):
    """Put back group_weights' result: the groups (made again where the mesh does not
    have them: from Blender 3.0 their names live on the mesh) with their vertices that the
    mesh still has."""
    count = len(obj.data.vertices)
    for name, members in weights.items():
        group = obj.vertex_groups.get(name) or obj.vertex_groups.new(name=name)
        by_weight = {}
        for v, w in members.items():
            if v < count:
                by_weight.setdefault(w, []).append(v)
        for w, vertices in by_weight.items():
            group.add(vertices, w, "REPLACE")


def replace_mesh_data(obj, vertices, faces):
    """Give obj a new mesh (vertices in world space), keeping its modifiers, materials and
    vertex groups. The vertices keep their indices (the pull appends the vertices it adds),
    so each group keeps its members."""
    old = obj.data
    weights = group_weights(obj)
    mesh = new_mesh(old.name, np.asarray(vertices) @ np.linalg.inv(np.array(obj.matrix_world))[:3, :3].T
                    + np.linalg.inv(np.array(obj.matrix_world))[:3, 3], faces)
    for material in old.materials:
        mesh.materials.append(material)
    obj.data = mesh
    for child in obj.children:  # the cage's control net draws the same mesh
        if child.data == old:
            child.data = mesh
    set_group_weights(obj, weights)
    if old.users == 0:
        bpy.data.meshes.remove(old)
    return mesh


# writing --------------------------------------------------------------------------------

def new_mesh(name, vertices, faces):
    """A mesh of equal-sized polygons (faces K×k int) or, with k == 2, of loose edges."""
    vertices = np.asarray(vertices, dtype=np.float32).reshape(-1, 3)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", vertices.ravel())
    faces = np.asarray(faces, dtype=np.int32)
    if faces.ndim == 2 and faces.shape[1] == 2:
        mesh.edges.add(len(faces))
        mesh.edges.foreach_set("vertices", faces.ravel())
    elif faces.size:
        arity = faces.shape[1]
        mesh.loops.add(faces.size)
        mesh.loops.foreach_set("vertex_index", faces.ravel())
        mesh.polygons.add(len(faces))
        mesh.polygons.foreach_set("loop_start", np.arange(0, faces.size, arity, dtype=np.int32))
        if _LOOP_TOTAL_WRITABLE:
            mesh.polygons.foreach_set("loop_total", np.full(len(faces), arity, dtype=np.int32))
    mesh.update(calc_edges=True)
    return mesh


def set_face_ints(mesh, name, values):
    attribute = mesh.attributes.new(name, "INT", "FACE")
    attribute.data.foreach_set("value", np.asarray(values, dtype=np.int32).ravel())


def set_face_colours(mesh, name, colours):
    """Colour per face (K×4), stored per corner so the viewport and Cycles show it."""
    sizes = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    attribute = mesh.color_attributes.new(name, "FLOAT_COLOR", "CORNER")
    corner = np.repeat(np.asarray(colours, dtype=np.float32), sizes, axis=0)
    attribute.data.foreach_set("color", corner.ravel())
    mesh.color_attributes.active_color = attribute
    if hasattr(mesh.color_attributes, "render_color_index"):
        mesh.color_attributes.render_color_index = mesh.color_attributes.active_color_index


def set_edge_creases(mesh, pairs, values):
    """Crease the edges between the vertex pairs; returns how many pairs are not edges."""
    edges = np.empty(len(mesh.edges) * 2, dtype=np.int32)
    mesh.edges.foreach_get("vertices", edges)
    index = results.edge_indices(edges.reshape(-1, 2), pairs)
    crease = np.zeros(len(mesh.edges), dtype=np.float32)
    found = index >= 0
    crease[index[found]] = np.asarray(values, dtype=np.float32).ravel()[found]
    if _EDGE_CREASE_PROPERTY:
        mesh.edges.foreach_set("crease", crease)
    else:
        attribute = (mesh.attributes.get("crease_edge")
                     or mesh.attributes.new("crease_edge", "FLOAT", "EDGE"))
        attribute.data.foreach_set("value", crease)
    return int(np.count_nonzero(~found))


def shade_smooth(mesh):
    if hasattr(mesh, "shade_smooth"):
        mesh.shade_smooth()
    else:
        mesh.polygons.foreach_set("use_smooth", np.ones(len(mesh.polygons), dtype=bool))


def add_subdivision(obj, subdivision):
    """Subdivision Surface modifier with every setting from the fitter written explicitly."""
    modifier = obj.modifiers.new("genbrep Subdivision", "SUBSURF")
    for name, value in results.subdivision_settings(subdivision).items():
        setattr(modifier, name, value)
    return modifier


def _colour_material(name, colour):
    """A material of one colour, in the viewport (Solid shading, colour Material) and in
    renders."""
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    material.diffuse_color = colour
    material.use_nodes = True
    shader = next((n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)
    if shader is not None:
        shader.inputs["Base Color"].default_value = colour
    return material


def _set_face_materials(mesh, face_material, materials):
    """materials: (name, RGBA) per material slot; face_material: the slot of each face."""
    for name, colour in materials:
        mesh.materials.append(_colour_material(name, colour))
    mesh.polygons.foreach_set("material_index", face_material)


def result_collection(scene, design_name):
    """The design's result collection, emptied (created and linked to the scene if needed)."""
    name = results.collection_name(design_name)
    collection = bpy.data.collections.get(name)
    if collection is None:
        collection = bpy.data.collections.new(name)
    else:
        remove_objects(collection)
    if collection.name not in scene.collection.children:
        scene.collection.children.link(collection)
    return collection


def remove_objects(collection):
    """Delete the collection's objects and the meshes only they used."""
    for obj in list(collection.objects):
        data = obj.data
        bpy.data.objects.remove(obj, do_unlink=True)
        if isinstance(data, bpy.types.Mesh) and data.users == 0:
            bpy.data.meshes.remove(data)


def remove_results(design_name):
    """Delete a design's result collection and its objects; False when there was none."""
    collection = bpy.data.collections.get(results.collection_name(design_name))
    if collection is None:
        return False
    remove_objects(collection)
    bpy.data.collections.remove(collection)
    return True


def _hide(obj):
    """Hidden in viewport (the eye, per view layer) and render; the user can show it again."""
    obj.hide_render = True
    try:
        obj.hide_set(True)
    except RuntimeError:  # not in the context's view layer (another scene)
        obj.hide_viewport = True


def _link(collection, name, mesh):
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    return obj


def write_results(scene, design_name, solid_roles, result, report_json):
    """Write a conversion result into the collection 'genbrep <design>'; returns it.

    solid_roles: native role of each solid index. The partition is always written; cages
    and the composed mesh when the result holds them. The most finished result is shown,
    the earlier ones are hidden (not deleted); once a solid is composed, the inputs (the
    objects with a role) are hidden in the viewport too, until the panel's Show Inputs.
    """
    collection = result_collection(scene, design_name)
    collection[results.DESIGN_PROPERTY] = design_name
    collection[results.REPORT_PROPERTY] = report_json
    try:
        shown = _write_partition(collection, design_name, solid_roles, result)
        cages = _write_cages(collection, design_name, result.get("cages") or [])
        composed = _write_composed(collection, design_name, result.get("composed"),
                                   solid_roles)
    except Exception:
        remove_objects(collection)
        raise
    if composed is not None or cages:
        for obj in shown:
            _hide(obj)
    if composed is not None:
        for cage in cages:
            cage.hide_render = True
        scene.genbrep_settings.show_inputs = False  # hides them (its update)
    return collection


def _write_partition(collection, design_name, solid_roles, result):
    # After §5.3 relaxation the later stages work on the relaxed design: show that one.
    design = result.get("relaxed") or result["design"]
    partition = design.get("partition") or result.get("partition") or {}
    faces = np.asarray(design["faces"], dtype=np.int32).reshape(-1, 3)
    mesh = new_mesh(results.partition_name(design_name), design["vertices"], faces)
    no_label = np.full(len(faces), -1, dtype=np.int32)
    face_solid = np.asarray(partition.get("face_solid", no_label), dtype=np.int32)
    face_component = np.asarray(partition.get("face_component", no_label), dtype=np.int32)
    set_face_ints(mesh, results.PARTITION_SOLID_ATTRIBUTE, face_solid)
    set_face_ints(mesh, results.PARTITION_COMPONENT_ATTRIBUTE, face_component)
    if "face_source" in design:
        set_face_ints(mesh, results.SOURCE_ATTRIBUTE, design["face_source"])
    set_face_colours(mesh, results.PARTITION_COLOR_ATTRIBUTE,
                     results.face_colours(face_solid, face_component, solid_roles))
    _set_face_materials(mesh, *results.partition_materials(face_solid, face_component,
                                                           solid_roles))
    written = [_link(collection, results.partition_name(design_name), mesh)]

    edges, _ = results.loop_edges(partition.get("loops") or [])
    if len(edges):
        used, local = np.unique(edges, return_inverse=True)
        vertices = np.asarray(design["vertices"]).reshape(-1, 3)[used]
        loops = new_mesh(results.loops_name(design_name), vertices, local.reshape(-1, 2))
        written.append(_link(collection, results.loops_name(design_name), loops))
    written.extend(_write_field(collection, design_name, design, face_solid, result.get("field")))
    return written


def _write_field(collection, design_name, design, face_solid, field):
    """The cross field as edges (a cross per organic face) and its singular vertices as
    points with an int attribute 'genbrep_index' (quarter turns). Hidden at first: dense."""
    if not field:
        return []
    points, edges = results.field_crosses(design["vertices"], design["faces"], field["direction"],
                                          np.asarray(face_solid) == -1)
    crosses = _link(collection, results.field_name(design_name),
                    new_mesh(results.field_name(design_name), points, edges))
    singular = np.asarray(field["singular_vertices"], dtype=np.int64)
    at = np.asarray(design["vertices"]).reshape(-1, 3)[singular]
    points_mesh = new_mesh(results.singularities_name(design_name), at, np.zeros((0, 2), np.int32))
    attribute = points_mesh.attributes.new("genbrep_index", "INT", "POINT")
    attribute.data.foreach_set("value", np.asarray(field["singular_index"], dtype=np.int32))
    singularities = _link(collection, results.singularities_name(design_name), points_mesh)
    for obj in (crosses, singularities):
        obj.hide_render = True
        obj.hide_set(True)
    return [crosses, singularities]


def _write_cages(collection, design_name, cages):
    written = []
    for index, cage in enumerate(cages):
        name = results.cage_name(design_name, cage, index)
        mesh = new_mesh(name, cage["vertices"], np.asarray(cage["faces"]).reshape(-1, 4))
        pairs = np.asarray(cage.get("crease_edges", ()), dtype=np.int32).reshape(-1, 2)
        if len(pairs):
            missing = set_edge_creases(mesh, pairs, cage.get("crease_values", ()))
            if missing:
                print(f"genbrep: {name}: {missing} crease edges are not cage edges; ignored")
        shade_smooth(mesh)
        component = int(cage.get("component", index))
        colour = results.component_colour(component)
        mesh.materials.append(_colour_material(results.component_material_name(component),
                                               colour))
        obj = _link(collection, name, mesh)
        obj[results.COMPONENT_PROPERTY] = component
        add_subdivision(obj, cage.get("subdivision"))
        off = np.asarray(cage.get("irregular_off_singularities", ()), dtype=np.int64).ravel()
        if off.size:
            group = obj.vertex_groups.new(name=results.OFF_SINGULARITIES_GROUP)
            group.add(off[off < len(mesh.vertices)].tolist(), 1.0, "REPLACE")
        _add_control_net(collection, obj, results.control_net_name(design_name, cage, index))
        written.append(obj)
    return written


def _add_control_net(collection, cage, name):
    """The cage's own mesh drawn as wire over its limit surface: a child object sharing the
    mesh, without the modifier, not selectable (clicks select the cage) and not rendered."""
    net = _link(collection, name, cage.data)
    net.parent = cage
    net.display_type = "WIRE"
    net.hide_select = True
    net.hide_render = True
    return net


def cage_objects(collection):
    """The cage objects of a result collection (not their control nets), in name order."""
    return sorted((o for o in collection.objects
                   if o.type == "MESH" and o.get(results.COMPONENT_PROPERTY) is not None),
                  key=lambda o: o.name)


def show_material_colours(screens):
    """Solid shading of the screens' 3D views colours by material, which shows the
    partition's and the cages' colours; views shaded otherwise are left as they are."""
    for screen in screens:
        for area in screen.areas:
            for space in area.spaces:
                if space.type == "VIEW_3D" and space.shading.type == "SOLID":
                    space.shading.color_type = "MATERIAL"


def write_recomposed(scene, design_name, solid_roles, cages_in, result, report_json):
    """After recompose(): the pulled cages replace the edited ones (same objects, modifiers
    kept) and the composed solid is replaced; returns the composed object or None."""
    collection = result_collection_existing(design_name)
    for obj, cage in zip(cages_in, result.get("cages") or []):
        mesh = replace_mesh_data(obj, cage["vertices"], np.asarray(cage["faces"]).reshape(-1, 4))
        pairs = np.asarray(cage.get("crease_edges", ()), dtype=np.int32).reshape(-1, 2)
        if len(pairs):
            set_edge_creases(mesh, pairs, cage.get("crease_values", ()))
        shade_smooth(mesh)
    old = collection.objects.get(results.composed_name(design_name))
    if old is not None:
        mesh = old.data
        bpy.data.objects.remove(old)
        if mesh.users == 0:
            bpy.data.meshes.remove(mesh)
    collection[results.REPORT_PROPERTY] = report_json
    return _write_composed(collection, design_name, result.get("composed"), solid_roles)


def result_collection_existing(design_name):
    return bpy.data.collections.get(results.collection_name(design_name))


def _write_composed(collection, design_name, composed, solid_roles):
    """The composed solid, its faces coloured by where they come from (the materials of the
    partition and the cages, so a cage drawn over it does not flicker)."""
    if not composed:
        return None
    faces = np.asarray(composed["faces"], dtype=np.int32).reshape(-1, 3)
    mesh = new_mesh(results.composed_name(design_name), composed["vertices"], faces)
    if "face_source" in composed:
        set_face_ints(mesh, results.SOURCE_ATTRIBUTE, composed["face_source"])
        _set_face_materials(mesh, *results.source_materials(composed["face_source"], solid_roles))
    else:
        mesh.materials.append(_colour_material("genbrep organic", results.ORGANIC_GREY))
    return _link(collection, results.composed_name(design_name), mesh)
