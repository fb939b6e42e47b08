"""Every relative link and image of the user guide (docs/src) and of README.md points at a file
that exists, and every #anchor at a heading of that file (mdBook's heading ids); every
{{#include}} names a file that exists. External links (http:, https:, mailto:) are not followed."""
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SRC = ROOT / "docs" / "src"
PAGES = sorted(SRC.rglob("*.md"))

LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
INCLUDE = re.compile(r"\{\{#include\s+([^}\s:]+)(?::[^}]*)?\}\}")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")


def prose(text: str) -> str:
    """The text outside fenced code blocks and inline code spans."""
    out, fenced = [], False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            out.append(re.sub(r"`[^`]*`", "", line))
    return "\n".join(out)


def heading_id(title: str) -> str:
    """mdBook's id of a heading: its text lower-cased, markup and punctuation other than '-' and
    '_' dropped, spaces turned into '-'."""
    title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title)  # a link keeps its text
    title = re.sub(r"<[^>]+>", "", title).replace("`", "")
    out = []
    for ch in title.strip().lower():
        if ch.isalnum() or ch in "-_":
            out.append(ch)
        elif ch.isspace():
            out.append("-")
    return "".join(out)


def anchors(path: pathlib.Path) -> set:
    ids, seen, fenced = set(), {}, False
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        m = None if fenced else HEADING.match(line)
        if m:
            base = heading_id(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            ids.add(base if n == 0 else f"{base}-{n}")
    return ids


def check_links(page: pathlib.Path, text: str) -> list:
    broken = []
    for target in LINK.findall(prose(text)):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target):
            continue  # http:, https:, mailto:
        path, _, frag = target.partition("#")
        dest = page if not path else (page.parent / path).resolve()
        if not dest.exists():
            broken.append(f"{target}: no such file")
        elif frag and dest.suffix == ".md" and frag not in anchors(dest):
            broken.append(f"{target}: no heading with id '{frag}' in {dest.name}")
    return broken


def test_the_guide_has_pages():
    assert (SRC / "SUMMARY.md").is_file()
    assert len(PAGES) > 30


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(SRC)) for p in PAGES])
def test_every_relative_link_of_the_guide_resolves(page):
    text = page.read_text(encoding="utf-8")
    broken = check_links(page, text)
    for inc in INCLUDE.findall(text):
        if not (page.parent / inc).is_file():
            broken.append(f"{{{{#include {inc}}}}}: no such file")
    assert not broken, f"{page.relative_to(ROOT)}: " + "; ".join(broken)


def test_every_page_is_in_the_summary():
    summary = (SRC / "SUMMARY.md").read_text(encoding="utf-8")
    listed = {(SRC / t).resolve() for t in LINK.findall(summary)}
    missing = [str(p.relative_to(SRC)) for p in PAGES if p.name != "SUMMARY.md" and p.resolve() not in listed]
    assert not missing, f"pages not in SUMMARY.md: {missing}"


def test_every_relative_link_of_the_readme_resolves():
    readme = ROOT / "README.md"
    broken = check_links(readme, readme.read_text(encoding="utf-8"))
    assert not broken, "README.md: " + "; ".join(broken)


def test_the_readme_stays_short():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").count("\n")
    assert lines <= 150, f"README.md has {lines} lines; the manual belongs in docs/src"


def test_no_link_check_passes_a_broken_link(tmp_path):
    """The checker itself: a missing file and a missing anchor are both caught."""
    (tmp_path / "a.md").write_text("# Title here\n\n## Second `x`, y\n")
    page = tmp_path / "b.md"
    text = "[ok](a.md#second-x-y) [gone](c.md) [bad](a.md#nope) ![img](x.svg) `[code](no.md)`"
    broken = check_links(page, text)
    assert broken == ["c.md: no such file", "a.md#nope: no heading with id 'nope' in a.md",
                      "x.svg: no such file"]
