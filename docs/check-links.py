"""Checks the relative links and images of the Markdown files outside the
guide (README.md, BENCHMARKS.md, ...): each target file exists and each
#anchor names a heading of its target, slugged as the guide's MkDocs build
slugs them. Exits 1 naming every broken link. Used by docs/build."""

import re
import sys
import unicodedata
from pathlib import Path

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^```.*?^```", re.S | re.M)


def slug(text: str) -> str:
    """Python-Markdown's toc slugify (what MkDocs uses for anchors)."""
    text = re.sub(r"`|\*", "", text)
    text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode()
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def anchors(path: Path) -> set[str]:
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    return {slug(m.group(1)) for m in re.finditer(r"^#+\s+(.*?)\s*$", text, re.M)}


def check(md: Path) -> list[str]:
    errors = []
    text = FENCE.sub("", md.read_text(encoding="utf-8"))
    for m in LINK.finditer(text):
        target = m.group(1)
        if re.match(r"[a-z]+:", target):
            continue  # http:, https:, mailto:
        file, _, anchor = target.partition("#")
        dest = (md.parent / file).resolve() if file else md.resolve()
        if not dest.exists():
            errors.append(f"{md}: link to {target}: {file} does not exist")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            errors.append(f"{md}: link to {target}: no heading #{anchor} in {file or md.name}")
    return errors


if __name__ == "__main__":
    problems = [e for name in sys.argv[1:] for e in check(Path(name))]
    for p in problems:
        print(f"error: {p}", file=sys.stderr)
    sys.exit(1 if problems else 0)
