"""The layout of the tests: the test of module ``impactcont/<package>/<module>.py`` is
``tests/<package>/test_<module>.py`` (``tests/test_<module>.py`` for a top-level module).

Tests that run a whole path across many modules are in ``tests/integration/``, those of the
studies in ``tests/studies/``; shared helpers stay at the root of ``tests/``. Every folder of
tests is a package (``__init__.py``) so that two test files may share a basename
(``tests/kernel/test_general.py`` and ``tests/orbit/test_general.py``); helpers are imported as
``from tests._scene_data import ...``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import impactcont

TESTS = Path(__file__).resolve().parent
PACKAGE = Path(impactcont.__file__).resolve().parent

# Folders of tests that are not named after a module: whole paths and the studies.
FREE_FOLDERS = {"integration", "studies"}
# Files at the root of tests/ that are not tests of a module: shared fixtures and helpers,
# and this file.
SHARED = {"__init__.py", "conftest.py", "_scene_data.py", "_fake_plugins.py", "reference_mp.py",
          "_made_up_branch.py", "_multi_impact_cases.py", "_layout_checks.py", "_ctrl_c.py",
          "_study_files.py", "test_layout.py"}
# Folders that hold no tests: reference data (tests/data/) and caches.
NOT_TESTS = {"data", "__pycache__"}

# Modules without a test file of their own, and why. Remove a module from this list when
# its test file is written (a stale entry fails the test below).
UNTESTED: set[str] = set()


def is_module(path: Path) -> bool:
    """A module that should have a test file: not a package's ``__init__.py`` nor
    ``__main__.py`` (``python -m impactcont``, tested through tests/test_cli.py)."""
    return path.suffix == ".py" and path.name not in ("__init__.py", "__main__.py")


def expected_test_file(module: Path, package: Path, tests: Path) -> Path:
    """The test file of ``module`` (a path under ``package``) under ``tests``."""
    rel = module.relative_to(package)
    return tests / rel.parent / f"test_{rel.name}"


def layout_errors(tests: Path, package: Path, untested: set[str]) -> list[str]:
    """What is out of place in ``tests`` for the modules of ``package``: one line each."""
    errors = []
    subpackages = {p.name for p in package.iterdir() if (p / "__init__.py").is_file()}
    for folder in sorted(p for p in tests.iterdir() if p.is_dir()):
        if folder.name in NOT_TESTS:
            continue
        if folder.name not in subpackages | FREE_FOLDERS:
            errors.append(f"{folder.relative_to(tests.parent)}/: no package {package.name}."
                          f"{folder.name}; tests go in a folder named after a subpackage, "
                          f"or in {sorted(FREE_FOLDERS)}")
        if not (folder / "__init__.py").is_file():
            errors.append(f"{folder.relative_to(tests.parent)}/ has no __init__.py (test files "
                          f"of different folders may share a basename only in packages)")
        for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
            if sub.name != "__pycache__":
                errors.append(f"{sub.relative_to(tests.parent)}/: one level of folders only")
    for path in sorted(tests.rglob("*.py")):
        rel = path.relative_to(tests)
        top = rel.parts[0]
        if top in NOT_TESTS or (len(rel.parts) > 1 and top in FREE_FOLDERS):
            continue
        if len(rel.parts) == 1 and path.name in SHARED:
            continue
        if path.name == "__init__.py":
            continue
        if not path.name.startswith("test_"):
            errors.append(f"{path.relative_to(tests.parent)}: a helper belongs at the root "
                          f"of tests/ (shared), not in a test folder")
            continue
        module = package / rel.parent / path.name.removeprefix("test_")
        if not module.is_file():
            errors.append(f"{path.relative_to(tests.parent)}: no module "
                          f"{module.relative_to(package.parent)} to be the test of")
    for module in sorted(p for p in package.rglob("*.py") if is_module(p)):
        if "__pycache__" in module.parts:
            continue
        name = module.relative_to(package).as_posix()
        has_test = expected_test_file(module, package, tests).is_file()
        if not has_test and name not in untested:
            errors.append(f"{module.relative_to(package.parent)} has no test file "
                          f"{expected_test_file(module, package, tests).relative_to(tests.parent)}")
        elif has_test and name in untested:
            errors.append(f"{name} has its test file now: take it off the list UNTESTED")
    for name in sorted(untested):
        if not (package / name).is_file():
            errors.append(f"UNTESTED lists {name}, which is not a module of "
                          f"{package.name}")
    return errors


def test_every_test_file_is_named_after_its_module_and_every_module_has_one() -> None:
    errors = layout_errors(TESTS, PACKAGE, UNTESTED)
    assert not errors, "\n".join(errors)


# -- the check itself, on a small tree: it must see each kind of misplaced file ------------
@pytest.fixture
def tree(tmp_path: Path) -> tuple[Path, Path]:
    package = tmp_path / "pkg"
    tests = tmp_path / "tests"
    for path in ("__init__.py", "cli.py", "kernel/__init__.py", "kernel/roots.py"):
        (package / path).parent.mkdir(parents=True, exist_ok=True)
        (package / path).touch()
    for path in ("__init__.py", "conftest.py", "test_cli.py", "kernel/__init__.py",
                 "kernel/test_roots.py", "integration/__init__.py",
                 "integration/test_anything.py"):
        (tests / path).parent.mkdir(parents=True, exist_ok=True)
        (tests / path).touch()
    return tests, package


def test_a_good_tree_passes(tree) -> None:
    tests, package = tree
    assert layout_errors(tests, package, set()) == []


@pytest.mark.parametrize(("add", "untested", "fragment"), [
    ("kernel/test_nonexistent.py", set(), "no module pkg/kernel/nonexistent.py"),
    ("test_roots.py", set(), "no module pkg/roots.py"),
    ("orbit/__init__.py", set(), "tests/orbit/: no package pkg.orbit"),
    ("kernel/_helper.py", set(), "a helper belongs at the root"),
    ("kernel/deeper/test_roots.py", set(), "one level of folders only"),
    (None, {"kernel/roots.py"}, "kernel/roots.py has its test file now"),
    (None, {"kernel/gone.py"}, "UNTESTED lists kernel/gone.py"),
])
def test_a_misplaced_file_is_named(tree, add, untested, fragment) -> None:
    tests, package = tree
    if add is not None:
        (tests / add).parent.mkdir(parents=True, exist_ok=True)
        (tests / add).touch()
    errors = layout_errors(tests, package, untested)
    assert any(fragment in e for e in errors), errors


def test_a_module_without_a_test_file_is_named(tree) -> None:
    tests, package = tree
    (tests / "kernel" / "test_roots.py").unlink()
    assert layout_errors(tests, package, set()) == [
        "pkg/kernel/roots.py has no test file tests/kernel/test_roots.py"]
    (tests / "kernel" / "__init__.py").unlink()
    assert any("tests/kernel/ has no __init__.py" in e
               for e in layout_errors(tests, package, {"kernel/roots.py"}))
