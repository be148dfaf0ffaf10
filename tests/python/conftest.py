"""pytest set-up for the compiled module: finds build/python and the scene writer."""
import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("GENBREP_BUILD", ROOT / "build"))
sys.path.insert(0, str(BUILD / "python"))
sys.path.insert(0, str(ROOT / "addon"))


@pytest.fixture(scope="session")
def native():
    import genbrep_native
    return genbrep_native


@pytest.fixture(scope="session")
def scenes(tmp_path_factory):
    """Analytic level-set scenes written by build/bin/make_scenes, read back as arrays."""
    out = tmp_path_factory.mktemp("scenes")
    subprocess.run([str(BUILD / "bin" / "make_scenes"), str(out), "0.06"], check=True)
    return out


def load_scene(native, folder):
    """(design dict, solids list, grid (origin, h), expected (components, loops))."""
    vertices, faces = native.read_mesh(str(folder / "design.obj"))
    design = {"name": folder.name, "vertices": vertices, "faces": faces}
    solids = []
    for path in sorted(folder.glob("*_keep_*.obj")) + sorted(folder.glob("*_seed.obj")):
        name, role = path.stem.split("_", 1)
        v, f = native.read_mesh(str(path))
        solids.append({"name": name, "role": role, "vertices": v, "faces": f})
    *origin, h = map(float, (folder / "grid.txt").read_text().split())
    components, loops = map(int, (folder / "expected.txt").read_text().split())
    return design, solids, (origin, h), (components, loops)
