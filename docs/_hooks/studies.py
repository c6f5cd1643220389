"""MkDocs hook: one page per study, made from ``studies/<name>/README.md`` and ``scene.toml``.

The studies live outside ``docs/``; this hook adds, for every directory of
``studies/`` that has a README or a scene:

* ``studies/<name>/index.md``: the README (or a stub naming the study), then
  the study's ``scene.toml`` and how to run it;
* the files the README links to that exist in the study directory (figures,
  the scene), at the same relative place, so that the README's links work;
  links to files of ``docs/`` point to their page of the site;
  links to files that are not there (outputs are not committed) become code
  text;
* ``studies/index.md``: the list of studies, and a "Studies" nav section.
"""

from __future__ import annotations

import logging
import os
import re
from pathlib import Path

from mkdocs.structure.files import File, Files

log = logging.getLogger("mkdocs.hooks.studies")

_LINK = re.compile(r"(!?)\[([^\]]*)\]\(([^)\s]+)\)")


def _root(config) -> Path:
    return Path(config["config_file_path"]).resolve().parent


def _studies(config) -> list[Path]:
    base = _root(config) / "studies"
    return sorted(p for p in base.iterdir() if p.is_dir()
                  and ((p / "README.md").is_file() or (p / "scene.toml").is_file()))


def _title(study: Path) -> str:
    readme = study / "README.md"
    if readme.is_file():
        for line in readme.read_text(encoding="utf-8").splitlines():
            if line.startswith("# "):
                return line[2:].strip()
    return study.name.replace("_", " ")


def on_config(config):
    studies = _studies(config)
    section = {"Studies": ["studies/index.md"]
               + [{_title(s): f"studies/{s.name}/index.md"} for s in studies]}
    config["nav"] = [*(config["nav"] or []), section]
    return config


def _page(study: Path, config, files: Files) -> str:
    readme = study / "README.md"
    if readme.is_file():
        text = readme.read_text(encoding="utf-8")
    else:
        text = f"# {_title(study)}\n\nThis study has no README yet.\n"

    def link(match: re.Match[str]) -> str:
        bang, label, target = match.groups()
        if re.match(r"^[a-z]+:|^#|^/", target):
            return match.group(0)
        target_path, hash_, fragment = target.partition("#")
        path = (study / target_path).resolve()
        docs = Path(config["docs_dir"]).resolve()
        if path.is_file() and path.is_relative_to(docs):
            # A page of the site: link to it from studies/<name>/index.md.
            page = Path(os.path.relpath(path, docs / "studies" / study.name)).as_posix()
            return f"{bang}[{label}]({page}{hash_}{fragment})"
        studies = study.resolve().parent
        if path.is_file() and path.is_relative_to(studies):
            # a file of this study or of another one (studies/<other>/...): its copy on
            # the site, a README as that study's page
            rel = path.relative_to(studies)
            if rel.name == "README.md" and len(rel.parts) == 2:
                page = Path(os.path.relpath(studies / rel.parts[0] / "index.md",
                                            study.resolve())).as_posix()
                return f"{bang}[{label}]({page}{hash_}{fragment})"
            uri = f"studies/{rel.as_posix()}"
            if files.get_file_from_path(uri) is None:
                files.append(File.generated(config, uri, abs_src_path=str(path)))
            return match.group(0)
        log.info("study %s: link to %s (not in the repository) shown as text", study.name,
                 target)
        return f"{label} (`{target}`)" if not bang else f"`{target}`"

    text = _LINK.sub(link, text)
    scene = study / "scene.toml"
    if scene.is_file():
        rel = f"studies/{study.name}/scene.toml"
        text += (f"\n\n## The scene\n\nRun it with `impactcont run {rel}` "
                 f"(see [the scene format](../../scenes.md)):\n\n```toml\n"
                 f"{scene.read_text(encoding='utf-8').rstrip()}\n```\n")
    return text


def on_files(files: Files, config) -> Files:
    studies = _studies(config)
    lines = ["# Studies", "",
             "Each study answers one question about the model. It is a scene "
             "(`studies/<name>/scene.toml`, run with `impactcont run`) with a README that "
             "reports what it found; some also have a `run.py` for checks a scene cannot "
             "express.", ""]
    for study in studies:
        files.append(File.generated(config, f"studies/{study.name}/index.md",
                                    content=_page(study, config, files)))
        lines.append(f"- [{_title(study)}]({study.name}/index.md): `studies/{study.name}/`")
    files.append(File.generated(config, "studies/index.md", content="\n".join(lines) + "\n"))
    return files
