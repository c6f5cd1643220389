"""Every study is a scene: ``studies/*/scene.toml`` exists, validates, and runs.

Validation is fast. Running a study's scene computes its branches, curves and
maps (1-5 s each once the kernel is compiled, about 25 s for all eight on a
2-core machine): those tests are marked ``slow``. They are cheap enough to stay
in the default run (CI grows by about 25 s); ``pytest -m "not slow"`` leaves
them out.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from impactcont.cli import EXIT_OK, main
from impactcont.scene import load_scene, read_output

ROOT = Path(__file__).resolve().parents[2]
STUDIES = sorted(p for p in (ROOT / "studies").iterdir() if p.is_dir()
                 and not p.name.startswith((".", "_")))


def test_every_study_directory_has_a_scene_and_says_how_to_run_it() -> None:
    assert len(STUDIES) >= 8
    for study in STUDIES:
        assert (study / "scene.toml").is_file(), f"{study.name} has no scene.toml"
        readme = (study / "README.md").read_text(encoding="utf-8")
        assert f"impactcont run studies/{study.name}/scene.toml" in readme, study.name


@pytest.mark.parametrize("study", STUDIES, ids=lambda p: p.name)
def test_study_scene_validates(study: Path, tmp_path: Path,
                               capsys: pytest.CaptureFixture[str]) -> None:
    scene = load_scene(study / "scene.toml")
    assert any(scene.sections.values()) and scene.plots
    # output.directory is relative to the scene file, not to the working directory
    assert scene.output_dir.is_absolute() and scene.output_dir.is_relative_to(study.resolve())
    assert main(["run", str(study / "scene.toml"), "--check", "--output",
                 str(tmp_path / "out")]) == EXIT_OK
    assert "valid scene" in capsys.readouterr().out
    assert not (tmp_path / "out").exists()  # --check computes and writes nothing


@pytest.mark.slow
@pytest.mark.parametrize("study", STUDIES, ids=lambda p: p.name)
def test_study_scene_runs(study: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    assert main(["-q", "run", str(study / "scene.toml"), "--output", str(out)]) == EXIT_OK
    scene = load_scene(study / "scene.toml", output=out)
    for key, entries in scene.sections.items():
        if entries:
            written = read_output(out / f"{key}.nc")
            assert list(written.datasets) == [e.name for e in entries]
    for plot in scene.plots:
        assert (out / plot.filename).stat().st_size > 1000
    assert "## Failures" not in (out / "summary.md").read_text(encoding="utf-8")
