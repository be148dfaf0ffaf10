"""The bad-input corpus: every kind of broken input, and the one line the user gets for it.

Each Case writes its input into a folder and states what `genbrep convert` (run in that
folder, with relative file names) must print and return; the same message must come from
the Python module (ConversionError with .code and .stage) and, for inputs Blender can
hold, from scripts/blender_convert.py. Kinds:

- "file": the file itself is broken; checked through the CLI and genbrep_native.read_mesh.
- "mesh": the files read fine but the geometry is wrong; CLI, genbrep_native.convert on
  the arrays read_mesh gives, and Blender objects made from those arrays.
- "arrays": geometry only arrays can carry (Blender objects, the module); no CLI.

An accepted input (exit 0) states the warning line instead of the error. The geometry is
small (a cube of 10 × 10 quads per side, two triangles each) so that every case runs in a
fraction of a second; `TOLERANCE` fixes d so that depths are measured against one value.
tests/bad_inputs/found/ holds inputs the fuzzer (bench/fuzz) found, each with its case.
Plain Python and numpy: no bpy, no genbrep_native.
"""

import dataclasses
import os
import struct

import numpy as np

TOLERANCE = 0.05


@dataclasses.dataclass
class Case:
    name: str
    kind: str                 # "file", "mesh" or "arrays"
    files: dict               # file name -> bytes, or (vertices, faces) written as OBJ
    solids: list              # [(file name, role)] with role keep_in, keep_out or seed
    message: str              # the error (or, with exit 0, the warning) without prefix
    code: str = "invalid_input"
    stage: str = "mesh"
    exit: int = 1
    design: str = "design.obj"
    arrays: dict = None       # kind "arrays": {"design": (V, F), solid name: (V, F)}

    def cli_args(self):
        args = ["convert", "--design", self.design, "--tolerance", str(TOLERANCE),
                "--until", "incidence", "--out", "out"]
        for name, role in self.solids:
            args += ["--" + role.replace("_", "-"), name]
        return args

    def line(self):
        """What the command line prints on standard error."""
        if self.exit == 0:
            return "genbrep: warning: " + self.message
        return f"genbrep: error in {self.stage}: {self.message}"

    def write(self, folder):
        os.makedirs(folder, exist_ok=True)
        for name, content in self.files.items():
            path = os.path.join(folder, name)
            if content is None:
                continue
            if isinstance(content, tuple):
                content = obj_text(*content).encode()
            with open(path, "wb") as out:
                out.write(content)


# geometry -----------------------------------------------------------------------------------

def box(lo, hi, n=1):
    """Closed, outward triangles of the box [lo, hi], n × n quads per side."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    vertices, faces = [], []
    t = np.linspace(0.0, 1.0, n + 1)
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, 1):
            base = len(vertices)
            for a in t:
                for b in t:
                    p = np.empty(3)
                    p[axis] = (lo if side == 0 else hi)[axis]
                    p[u] = lo[u] + a * (hi[u] - lo[u])
                    p[v] = lo[v] + b * (hi[v] - lo[v])
                    vertices.append(p)
            for i in range(n):
                for j in range(n):
                    a, b = base + i * (n + 1) + j, base + (i + 1) * (n + 1) + j
                    c, d = b + 1, a + 1
                    quad = [(a, b, c), (a, c, d)] if side == 1 else [(a, c, b), (a, d, c)]
                    faces.extend(quad)
    vertices = np.array(vertices)
    faces = np.array(faces, np.int32)
    # Weld the shared box edges so that the box is one closed surface.
    keys = {tuple(np.round(p, 12)): None for p in vertices}
    index = {k: i for i, k in enumerate(keys)}
    remap = np.array([index[tuple(np.round(p, 12))] for p in vertices])
    return np.array(list(keys), float), remap[faces].astype(np.int32)


def merge(*meshes):
    vertices, faces, offset = [], [], 0
    for v, f in meshes:
        vertices.append(v)
        faces.append(f + offset)
        offset += len(v)
    return np.vstack(vertices), np.vstack(faces).astype(np.int32)


def obj_text(vertices, faces):
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, float).tolist()]
    lines += ["f %d %d %d" % tuple(np.asarray(f) + 1) for f in faces]
    return "\n".join(lines) + "\n"


def binary_stl(vertices, faces, count=None):
    """A binary STL of the triangles; `count` overrides the header's triangle count."""
    data = bytearray(b"genbrep test".ljust(80, b" "))
    data += struct.pack("<I", len(faces) if count is None else count)
    for f in faces:
        data += struct.pack("<3f", 0, 0, 0)
        for c in f:
            data += struct.pack("<3f", *vertices[c])
        data += b"\0\0"
    return bytes(data)


def binary_ply(vertices, faces):
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
              "property float y\nproperty float z\nelement face %d\n"
              "property list uchar int vertex_indices\nend_header\n" % (len(vertices), len(faces)))
    body = b"".join(struct.pack("<3f", *p) for p in vertices)
    body += b"".join(struct.pack("<B3i", 3, *f) for f in faces)
    return header.encode() + body


DESIGN = box((-1, -1, -1), (1, 1, 1), 10)
PAD = box((0.6, -0.3, -0.3), (1, 0.3, 0.3))             # keep-in on the design's +x face
TET = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float),
       np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], np.int32))
WITH_PAD = [("pad.obj", "keep_in")]


def design_with(vertices=None, faces=None):
    v, f = DESIGN
    return (v if vertices is None else vertices, f if faces is None else faces)


def flipped(mesh):
    v, f = mesh
    return v, f[:, [0, 2, 1]]


def zero_area_design():
    """The design with one edge split by its midpoint into a zero-area triangle."""
    v, f = DESIGN
    a, b, c = f[0]
    m = len(v)
    v = np.vstack([v, (v[a] + v[b]) / 2])
    f = np.vstack([[[a, m, c], [m, b, c], [a, b, m]], f[1:]]).astype(np.int32)
    return v, f


def pushed_through(mesh):
    """The box `mesh` with one inner vertex of its top face pushed down through its bottom."""
    v, f = mesh
    v = v.copy()
    lo, hi = v.min(axis=0), v.max(axis=0)
    mid = (lo + hi) / 2
    inner = (v[:, 2] == hi[2]) & np.all(np.abs(v[:, :2] - mid[:2]) < (hi - lo)[:2] / 4, axis=1)
    top = np.flatnonzero(inner)[0]
    v[top, 2] = lo[2] - (hi[2] - lo[2]) / 4
    return v, f


def non_manifold_edge_design():
    v, f = DESIGN
    other = box((1, 1, -1), (3, 3, 1), 10)   # shares the edge x = y = 1 with the design
    return merge((v, f), other)


def random_bytes(size, seed=7):
    return np.random.default_rng(seed).integers(0, 256, size, dtype=np.uint8).tobytes()


def cases():
    pad = {"pad.obj": PAD}
    v, f = DESIGN
    stl = binary_stl(*TET)
    ply = binary_ply(*TET)
    return [
        # files ------------------------------------------------------------------------------
        Case("missing_file", "file", {}, [], "cannot open 'design.obj': no such file",
             code="file_error"),
        Case("directory", "file", {}, [], "cannot read 'design.obj': it is a directory, not a "
             "mesh file", code="file_error"),
        Case("unreadable", "file", {"design.obj": obj_text(*DESIGN).encode()}, [],
             "cannot open 'design.obj': permission denied", code="file_error"),
        Case("empty_file", "file", {"design.obj": b""}, [], "'design.obj' is empty (0 bytes)"),
        Case("random_bytes", "file", {"design.obj": random_bytes(20000)}, [],
             "'design.obj' is not a text OBJ file: byte 6 is 0x06 (binary data)"),
        Case("random_bytes_stl", "file", {"design.stl": random_bytes(20000)}, [],
             "'design.stl' is not an STL file: it does not start with 'solid', and as binary STL "
             "its header announces 3506691144 triangles (175334557284 bytes) but the file has "
             "20000 bytes", design="design.stl"),
        Case("truncated_binary_stl", "file", {"design.stl": stl[:-30]}, [],
             "'design.stl' is truncated: it does not start with 'solid', and as binary STL its "
             "header announces 4 triangles (284 bytes) but the file has 254 bytes",
             design="design.stl"),
        Case("truncated_binary_ply", "file", {"design.ply": ply[:-20]}, [],
             "'design.ply' is truncated: its header announces 4 vertices and 4 faces; the data "
             "ends in face 2", design="design.ply"),
        Case("wrong_header_ply", "file", {"design.ply": b"plx\n" + ply[4:]}, [],
             "'design.ply' does not start with 'ply': not a PLY file (its first line is 'plx')",
             design="design.ply"),
        Case("wrong_header_off", "file", {"design.off": b"OFX\n4 4 0\n0 0 0\n"}, [],
             "'design.off' does not start with OFF: not an OFF file (it starts with 'OFX')",
             design="design.off"),
        Case("unknown_extension", "file", {"design.xyz": b"v 0 0 0\n"}, [],
             "cannot read 'design.xyz': the extension '.xyz' is none of .obj, .ply, .stl and "
             ".off", code="file_error", design="design.xyz"),
        Case("face_index_out_of_range", "file",
             {"design.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"}, [],
             "'design.obj' line 4: face 1 uses vertex 7 but the file has 3 vertices"),
        Case("zero_index", "file", {"design.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"}, [],
             "'design.obj' line 4: face 1 uses vertex 0; OBJ numbers vertices from 1"),
        Case("negative_index", "file",
             {"design.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -9\n"}, [],
             "'design.obj' line 4: face 1 uses vertex -9, which counts back past the first "
             "vertex (3 vertices before it)"),
        Case("ply_index_out_of_range", "file",
             {"design.ply": b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
              b"property float y\nproperty float z\nelement face 1\nproperty list uchar int "
              b"vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n"}, [],
             "'design.ply' face 0 uses vertex 5 but the file has 3 vertices (PLY numbers them "
             "from 0)", design="design.ply"),
        Case("nan_coordinate", "file", {"design.obj": b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"},
             [], "'design.obj' line 2: vertex 2 has a NaN coordinate ('nan')"),
        Case("infinite_coordinate", "file",
             {"design.obj": b"v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n"}, [],
             "'design.obj' line 2: vertex 2 has an infinite coordinate ('inf')"),
        Case("huge_coordinate", "file",
             {"design.obj": b"v 0 0 0\nv 1e300 0 0\nv 0 1 0\nf 1 2 3\n"}, [],
             "'design.obj' line 2: vertex 2 has a coordinate of 1e+300, beyond \u00b11e+12"),
        Case("malformed_coordinate", "file",
             {"design.obj": b"v 0 0 0\nv 1 two 0\nv 0 1 0\nf 1 2 3\n"}, [],
             "'design.obj' line 2: vertex 2 has a coordinate 'two' that is not a number"),
        Case("stl_nan", "file",
             {"design.stl": binary_stl(np.array([[0, 0, 0], [np.nan, 0, 0], [0, 1, 0]]),
                                       np.array([[0, 1, 2]]))}, [],
             "'design.stl' triangle 0 has a NaN coordinate ('nan')", design="design.stl"),
        # geometry ---------------------------------------------------------------------------
        Case("collinear", "mesh",
             {"design.obj": (np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float),
                             TET[1]), **pad}, WITH_PAD,
             "design 'design' is degenerate: all its 4 triangles have zero area (its vertices "
             "lie on one line)"),
        Case("zero_area_triangles", "mesh", {"design.obj": zero_area_design(), **pad}, WITH_PAD,
             "design 'design': 1 zero-area triangles kept", code=None, exit=0),
        Case("duplicate_faces", "mesh", {"design.obj": (v, np.vstack([f, f[5:6]])), **pad},
             WITH_PAD, "design 'design' has 1 duplicate triangle (face 1200 has the corners of "
             "face 5, counted from 0)"),
        Case("open_design", "mesh", {"design.obj": (v, f[:-1]), **pad}, WITH_PAD,
             "design 'design' is open: 3 boundary edges (the surface is open; the first at "
             "(0.9, 1, 1))"),
        Case("non_manifold_edge", "mesh", {"design.obj": non_manifold_edge_design(), **pad},
             WITH_PAD, "design 'design' is not a closed 2-manifold surface: 10 non-manifold edges "
             "(three or more triangles; the first at (1, 1, -0.9)), 11 non-manifold vertices (the "
             "first at (1, 1, -1))"),
        Case("non_manifold_vertex", "mesh",
             {"design.obj": merge(DESIGN, box((1, 1, 1), (2, 2, 2), 10)), **pad}, WITH_PAD,
             "design 'design' is not a closed 2-manifold surface: 1 non-manifold vertex (at "
             "(1, 1, 1))"),
        Case("inconsistent_orientation", "mesh",
             {"design.obj": (v, np.vstack([f[:7], f[7:8, [0, 2, 1]], f[8:]])), **pad}, WITH_PAD,
             "design 'design' is not a closed 2-manifold surface: 3 edges with inconsistent "
             "orientation (the first at (-1, -1, -0.3))"),
        Case("inside_out_design", "mesh", {"design.obj": flipped(DESIGN), **pad}, WITH_PAD,
             "design 'design' was inside out; its triangles were flipped", code=None, exit=0),
        Case("overlapping_shells", "mesh",
             {"design.obj": merge(DESIGN, box((0.05, 0.05, 0.05), (2, 2, 2), 7)), **pad},
             WITH_PAD, "design 'design' has 2 shells that overlap: 102 pairs of triangles cross "
             "(the first: faces 310 and 1403, near (1, 0.133333, 0.0666667))"),
        Case("self_intersecting_design", "mesh", {"design.obj": pushed_through(DESIGN), **pad},
             WITH_PAD, "design 'design' intersects itself: 18 pairs of triangles cross (the "
             "first: faces 844 and 1044, near (-0.466667, -0.533333, -1))"),
        Case("open_solid", "mesh", {"design.obj": DESIGN, "pad.obj": (PAD[0], PAD[1][1:])},
             WITH_PAD, "keep-in 'pad' is open: 3 boundary edges (the surface is open; the first "
             "at (0.6, 0, -0.3))"),
        Case("self_intersecting_solid", "mesh",
             {"design.obj": DESIGN,
              "pad.obj": pushed_through(box((0.6, -0.3, -0.3), (1, 0.3, 0.3), 3))}, WITH_PAD,
             "keep-in 'pad' intersects itself: 18 pairs of triangles cross (the first: faces 72 "
             "and 90, near (0.688889, -0.233333, -0.3))"),
        Case("solid_far_from_design", "mesh",
             {"design.obj": DESIGN, "pad.obj": box((10, 10, 10), (11, 11, 11))}, WITH_PAD,
             "keep-in 'pad' is outside the design: it is 15.6 from it at its nearest, and no "
             "design vertex lies within d = 0.05 of it; the design must contain every keep-in",
             code=None, exit=0),
        Case("keep_in_inside_keep_out", "mesh",
             {"design.obj": DESIGN, **pad, "bore.obj": box((0.4, -0.5, -0.5), (1.5, 0.5, 0.5))},
             WITH_PAD + [("bore.obj", "keep_out")],
             "keep-in 'pad' lies inside keep-out 'bore': all its 8 vertices are in it, up to 0.2 "
             "deep; material cannot be both required and forbidden there", stage="incidence"),
        Case("keep_in_not_contained", "mesh",
             {"design.obj": DESIGN, "pad.obj": box((0.5, -0.6, -0.6), (2, 0.6, 0.6))}, WITH_PAD,
             "keep-in 'pad' is not inside the design: 25 design vertices lie up to 0.5 deep "
             "inside it (the first at (1, -0.4, -0.4)); the design must contain every keep-in",
             code=None, exit=0),
        Case("material_in_keep_out", "mesh",
             {"design.obj": DESIGN, **pad, "bore.obj": box((-2, -0.5, -0.5), (-0.5, 0.5, 0.5))},
             WITH_PAD + [("bore.obj", "keep_out")],
             "keep-out 'bore' has material inside it: 9 design vertices lie up to 0.5 deep inside "
             "it (the first at (-1, -0.2, -0.2)); a keep-out must stay empty", code=None, exit=0),
        Case("no_solids", "mesh", {"design.obj": DESIGN}, [],
             "design 'design' has no solids (keep-in, keep-out or seed): every part of it is "
             "organic and composed from its cage as a closed shell", code=None, exit=0),
        # arrays only ------------------------------------------------------------------------
        Case("nan_vertex_array", "arrays", {}, WITH_PAD,
             "design 'design' has 1 vertex with NaN or infinite coordinates (first: vertex 3)",
             arrays={"design": (np.where(np.arange(len(v))[:, None] == 3, np.nan, v), f),
                     "pad": PAD}),
        Case("huge_vertex_array", "arrays", {}, WITH_PAD,
             "design 'design' has 602 vertices with coordinates beyond \u00b11e+12 (first: vertex "
             "0 at (-1e+13, -1e+13, -1e+13)): scale it to smaller units",
             arrays={"design": (v * 1e13, f), "pad": (PAD[0] * 1e13, PAD[1])}),
        Case("no_faces_array", "arrays", {}, WITH_PAD, "design 'design' is empty: it has no "
             "triangles", arrays={"design": (v, np.zeros((0, 3), np.int32)), "pad": PAD}),
    ]


def by_name():
    return {c.name: c for c in cases()}


def inputs(case, folder, read_mesh):
    """(design dict, solids list) of a "mesh" or "arrays" case, as genbrep_native.convert
    takes them: files read with `read_mesh` from `folder`, names their file stems."""
    def named(name, mesh):
        vertices, faces = mesh
        return {"name": name, "vertices": np.asarray(vertices, np.float64),
                "faces": np.asarray(faces, np.int32)}
    stem = lambda file: os.path.splitext(file)[0]
    if case.kind == "arrays":
        load = lambda file: case.arrays["design" if file == case.design else stem(file)]
    else:
        load = lambda file: read_mesh(os.path.join(folder, file))
    design = named(stem(case.design), load(case.design))
    solids = [dict(named(stem(file), load(file)), role=role) for file, role in case.solids]
    return design, solids


def prepare(case, folder):
    """Writes the case into `folder`, with the directory and unreadable file it may need."""
    case.write(folder)
    path = os.path.join(folder, case.design)
    if case.name == "directory":
        os.makedirs(path, exist_ok=True)
    if case.name == "unreadable":
        os.chmod(folder, 0o755)
        os.chmod(path, 0)
