"""The project as a user meets it: install layout, import cost, README/CI, command line."""

from __future__ import annotations

import copy
import importlib.util
import pickle
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("pyvista", "matplotlib", "trimesh", "embreex", "vtk", "numba", "skimage")


def _run(*args, check=True):
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, check=check,
                          cwd=ROOT)


def test_import_is_light():
    # The heavy packages are installed in the test environment, so their absence from
    # sys.modules after `import meshladar` means meshladar did not import them.
    for name in HEAVY:
        assert importlib.util.find_spec(name) is not None, f"{name} should be installed for tests"
    code = ("import sys, meshladar; "
            f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = _run("-c", code).stdout.strip()
    assert out == "", f"import meshladar pulled in: {out}"


#: What a one-view `meshladar simulate` of a binary STL does not need, so does not import:
#: the studies, the fits, the scanner's modules (scipy's interpolation with them), scipy's
#: statistics and matplotlib, trimesh (numpy reads the file; trimesh would bring scipy's
#: optimisers, graphs, images and spatial trees with it), and numba (such a run calls no
#: compiled loop, and the modules of compiled loops are imported at their first use).
NOT_FOR_SIMULATE = ("meshladar.studies", "meshladar.fit", "meshladar.scan.run",
                    "meshladar.scan.geiger", "meshladar.scan.platforms", "scipy.interpolate",
                    "scipy.stats", "matplotlib", "trimesh", "scipy.spatial", "scipy.optimize",
                    "numba")


def test_a_one_view_simulate_imports_only_what_it_uses(tmp_path):
    """The command line loads a command's heavy modules when that command runs: a mesh
    simulated from one view (the cold start of the command line) imports none of
    NOT_FOR_SIMULATE."""
    ball, result = str(tmp_path / "ball.stl"), str(tmp_path / "ball.npz")
    _run("-c", f"import trimesh; trimesh.creation.icosphere(2).export({ball!r})")
    code = ("import sys; from meshladar.cli import main; "
            f"assert main(['simulate', {ball!r}, '--material', 'dark_gray', '--views', '1', "
            f"'-o', {result!r}]) == 0; "
            f"print(','.join(m for m in {NOT_FOR_SIMULATE!r} if m in sys.modules))")
    out = _run("-c", code).stdout
    assert out.splitlines()[-1] == "", f"simulate pulled in: {out}"


def test_a_deferred_module_imports_at_its_first_attribute(tmp_path, monkeypatch):
    """meshladar._lazy.deferred_module: nothing is imported until an attribute is looked
    up; then the module's own attribute, patched ones included."""
    from meshladar._lazy import deferred_module

    (tmp_path / "meshladar_probe_kernels.py").write_text("LOADS = 1\ndef twice(x):\n"
                                                         "    return 2 * x\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "meshladar_probe_kernels", raising=False)
    probe = deferred_module("meshladar_probe_kernels")
    assert "meshladar_probe_kernels" not in sys.modules
    assert repr(probe) == "<deferred module 'meshladar_probe_kernels'>"
    assert probe.twice(21) == 42 and "meshladar_probe_kernels" in sys.modules
    monkeypatch.setattr(sys.modules["meshladar_probe_kernels"], "twice", lambda x: -x)
    assert probe.twice(21) == -21                  # looked up in the module at each use
    with pytest.raises(AttributeError, match="nothing"):
        probe.nothing
    for copied in (copy.copy(probe), pickle.loads(pickle.dumps(probe))):   # (they recursed)
        assert repr(copied) == repr(probe) and copied.twice(2) == -2
    monkeypatch.delitem(sys.modules, "meshladar_probe_kernels")


def test_subpackages_install_from_top_level_folders():
    import meshladar.phantoms
    import meshladar.viz

    assert Path(meshladar.phantoms.__file__).parent == ROOT / "phantoms"
    assert Path(meshladar.viz.__file__).parent == ROOT / "viz"
    assert meshladar.phantoms.MATERIALS_TOML.is_file()


def test_readme_opens_with_two_commands_and_ci_runs_the_second():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"```bash\n(.*?)```", readme, re.S)
    assert block is not None and readme.index("```bash") < readme.index("\n## ")
    commands = [line for line in block.group(1).splitlines() if line.strip()]
    assert len(commands) == 2
    assert "meshladar paper" in commands[0] and "pytest" in commands[1]
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert commands[1] in ci.splitlines()


def test_pytest_is_strict():
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert cfg["filterwarnings"] == ["error"]
    assert "--strict-markers" in cfg["addopts"]


def test_cli_demo_prints_paper_values():
    out = _run("-m", "meshladar", "demo", "--angles-deg", "0,5,90").stdout
    # aluminium at normal incidence: ρs(0)(1 + e²)/(4π e²) + ρd/(πG²) = 651.125 sr⁻¹
    assert re.search(r"aluminum.*\n.*\n\s+0\.000\s+651\.12", out)
    assert "dark_gray" in out and "G(b)=0.963114" in out
    assert "nan" not in out.lower() and "inf" not in out.lower()


def test_cli_materials_lists_table(tmp_path):
    out = _run("-m", "meshladar", "materials").stdout
    assert re.search(r"^aluminum\s+both\s+0\.047\s+0\.53\s+0\.1\s+0\.007", out, re.M)
    bad = tmp_path / "bad.toml"
    bad.write_text("[x]\nrho_d = 3\nepsilon = 0\nb = 0\ne = 1\n")
    res = _run("-m", "meshladar", "materials", str(bad), check=False)
    assert res.returncode == 2
    assert res.stderr.strip().count("\n") == 0 and "Traceback" not in res.stderr
    assert "bad.toml: material [x]: rho_d must be in [0, 1]; got 3.0" in res.stderr


@pytest.mark.parametrize("args", [["demo", "--angles-deg", "a,b"], ["nosuch"], []])
def test_cli_bad_arguments_exit_nonzero_without_traceback(args):
    res = _run("-m", "meshladar", *args, check=False)
    assert res.returncode == 2
    assert "Traceback" not in res.stderr and "error" in res.stderr


def test_no_public_name_shadows_a_submodule():
    # `import meshladar.trace as t` once returned the function: the mesh model's module is
    # meshladar.forward.mesh, and meshladar.trace is only the function
    import importlib
    import pkgutil
    import sys

    import meshladar as ml

    assert callable(ml.trace) and not isinstance(ml.trace, type(ml))
    assert importlib.import_module("meshladar.forward").trace is ml.trace
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("meshladar.trace")
    # no submodule is shadowed by a public name, and none is named like the standard
    # library (io excepted: meshladar.io is the result files, as scipy.io is scipy's)
    packages = [ml] + [importlib.import_module(f"meshladar.{p}") for p in
                       ("raytrace", "weighing", "forward", "reconstruct", "fit", "studies",
                        "brdf", "meshes", "cli")]
    for pkg in packages:
        for mod in pkgutil.iter_modules(pkg.__path__):
            if mod.name == "__main__" or mod.name in ml._DEPRECATED or (
                    pkg is not ml and f"{pkg.__name__}.{mod.name}".endswith(
                        ("raytrace.model", "raytrace.hits"))):
                continue
            module = importlib.import_module(f"{pkg.__name__}.{mod.name}")
            public = getattr(pkg, mod.name, module)
            assert public is module, f"{pkg.__name__}.{mod.name} is not the module"
            assert mod.name not in sys.stdlib_module_names or mod.name == "io", \
                f"{mod.name} shadows the stdlib"


def test_dir_lists_the_public_names_the_layout_page_tabulates():
    """dir(meshladar) holds its public names and submodules and nothing stray (it listed
    ``annotations``, the __future__ feature), and the guide's Layout table names each
    (it lacked ``lrcs`` and ``scan``)."""
    import meshladar as ml

    public = {n for n in dir(ml) if not n.startswith("_")}
    assert public == set(ml._NAMES) | set(ml._SUBMODULES)
    table = (ROOT / "docs" / "guide" / "layout.md").read_text(encoding="utf-8")
    rows = table[table.index("| `ml.<name>` | from |"):].split("\n\n")[0]
    named = set(re.findall(r"`(\w+)`", rows))
    assert public <= named, sorted(public - named)


def test_every_public_submodule_is_an_attribute_and_old_names_warn():
    # one lazy table: ml.<name> for every public submodule, imported on first use; the
    # modules that moved are deprecated aliases that name their new home
    code = ("import sys, warnings, meshladar as ml\n"
            "warnings.simplefilter('error')\n"
            "for name in ml._SUBMODULES:\n"
            "    assert getattr(ml, name).__name__ == 'meshladar.' + name, name\n"
            "for old, new in ml._DEPRECATED.items():\n"
            "    try:\n"
            "        getattr(ml, old)\n"
            "    except DeprecationWarning as w:\n"
            "        assert 'meshladar.' + new in str(w), (old, str(w))\n"
            "    else:\n"
            "        raise AssertionError(old + ' did not warn')\n"
            "print(len(ml._SUBMODULES), len(ml._DEPRECATED))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert res.stdout.split() == ["30", "17"]


def test_moved_entry_points_name_a_home_that_holds_them():
    # meshladar.raytrace.first_hits named meshladar.forward.first_hits, which is not there
    raytrace = importlib.import_module("meshladar.raytrace")
    for name in raytrace._ENTRY_POINTS:
        with pytest.warns(DeprecationWarning) as record:
            old = getattr(raytrace, name)
        home = re.search(r"use (meshladar\.[\w.]+)", str(record[0].message)).group(1)
        module, attr = home.rsplit(".", 1)
        assert getattr(importlib.import_module(module), attr) is old, (name, home)


def test_a_deprecated_module_warns_at_the_users_import_line():
    # the warning points at the line that imported the old name, not at the import
    # machinery, so the default filters show it to the user
    sys.modules.pop("meshladar.results", None)
    with pytest.warns(DeprecationWarning, match="meshladar.io") as record:
        importlib.import_module("meshladar.results")
    assert record[0].filename == __file__


def test_every_engine_package_is_installed():
    # a non-editable install ships only the packages pyproject.toml lists: every folder of
    # the engine with an __init__.py must be among them, or `pip install meshladar` lacks it
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for p in (ROOT / "meshladar").rglob("__init__.py")}
    assert found <= listed, sorted(found - listed)
    assert {"meshladar.phantoms", "meshladar.viz"} <= listed


def test_the_guide_views_formula_gives_the_numbers_it_states():
    # "4π (n/2)² / (2σ)² directions ... (about 12,900 at 128³ with σ = 1, 1,400 at 64³ with
    # σ = 1.5)": the stated numbers are the formula's, to the rounding the text uses
    import math

    page = (ROOT / "docs" / "guide" / "beyond_range.md").read_text(encoding="utf-8")
    stated = re.findall(r"([\d,]+) at (\d+)³ with σ = ([\d.]+)", page)
    assert len(stated) == 2
    for count, n, sigma in stated:
        views = 4 * math.pi * (int(n) / 2) ** 2 / (2 * float(sigma)) ** 2
        assert abs(int(count.replace(",", "")) - views) <= 0.01 * views, (count, views)


def test_the_scanner_loads_on_first_use_and_its_modules_are_attributes():
    """meshladar.scan names its public names and its modules without importing them at
    the command line's start; each resolves on first use, as the package used to."""
    code = ("import sys, meshladar.cli, meshladar as ml; "
            "before = 'meshladar.scan.run' in sys.modules; "
            "from meshladar.scan import *; "
            "print(before, scan.__module__, Platform.__module__, ml.scan.points.__name__, "
            "sorted(set(ml.scan.__all__) - set(dir(ml.scan))))")
    assert _run("-c", code).stdout.split() == [
        "False", "meshladar.scan.run", "meshladar.scan.platforms", "meshladar.scan.points",
        "[]"]


def test_test_modules_have_unique_names():
    # the suite imports test modules by their file name (no packages): two of one name in
    # different folders stop the whole collection
    names = [p.name for p in (ROOT / "tests").rglob("test_*.py")]
    assert len(names) > 100
    assert sorted({n for n in names if names.count(n) > 1}) == []
