#!/usr/bin/env python3
"""Point every citation of the old, external model specification at docs/model.md.

    python3 tools/model_refs.py ROOT [--model docs/model.md] [--check]

The model used to live in a file outside the repository (a shared ``spec``
folder, cited as "<SPEC> section 4", "<SPEC> sec. 4", "(<SPEC> 5.1)",
"<SPEC> eq. (3)", a bare "<SPEC>" or a relative link to the file, where
<SPEC> is that file's name).  This script rewrites each citation under ROOT
into a citation of the model page, with the anchor of the cited section
taken from the page's own numbered headings ("## 4. Forcing",
"### 4.2 Regenerative cutting"):

- Markdown files get a relative link from the file's own folder, e.g.
  ``[model, section 4.2](../docs/model.md#42-regenerative-cutting)``; inside
  code spans and fenced blocks, plain text;
- every other file (Python, TOML, ...) gets plain text,
  ``docs/model.md, section 4.2``, with the whitespace and line breaks of the
  original kept, so wrapped docstrings and string literals stay valid.

Nothing depends on where files are today: the files are found by walking
ROOT, and the anchors are read from the model page (``--model``, relative to
ROOT).  Running it again changes nothing.  It prints the number of citations
rewritten per file, then every line that still refers to the external spec;
the exit status is 1 if any does (or, with ``--check``, if anything would be
rewritten), 2 on a usage error, else 0.  Standard library only.
"""

from __future__ import annotations

import argparse
import os
import re
import sys

# Spelled in pieces so this file does not cite the external spec itself.
SPEC_NAME = "MODEL" + ".md"
SPEC_DIR = "shared/" + "spec"

TEXT_SUFFIXES = (".py", ".md", ".toml", ".txt", ".html", ".cfg", ".yml", ".yaml", ".rst",
                 ".ini", ".json", ".ipynb", ".in", ".sh")
SKIP_DIRS = {"node_modules", "__pycache__", "build", "dist", "site", "out", "venv"}

_SPEC = re.escape(SPEC_NAME)
#: the spec's name, with any folder before it and any anchor after it
PATH = rf"(?<![\w./-])(?:[\w.-]+/)*{_SPEC}(?:#[\w.-]*)?"
NUM = r"\d+(?:\.\d+)*(?![\d.]*\d)"
ITEM = rf"(?:\({NUM}\)|{NUM})"
LIST_SEP = r"\s*(?:,|-|–|\band\b|\bto\b|&)\s*"
KEYWORD = r"(?i:sections?|secs?\.|§|eqs?\.|equations?)"
#: a citation: the path, then optionally a keyword and section numbers, or a bare number
CITATION = re.compile(
    rf"(?P<path>{PATH})"
    rf"(?:(?P<ws>,?(?=\s)[ \t]*\n?[ \t]*)(?P<kw>{KEYWORD})(?P<ws2>[ \t]*\n?[ \t]*)"
    rf"(?P<nums>{ITEM}(?:{LIST_SEP}{ITEM})*)"
    rf"|(?P<bws>[ \t]+)(?P<bare>{NUM})(?![\w-])"
    rf"|(?P<ows>,?(?=\s)[ \t]*\n?[ \t]*)(?P<okw>{KEYWORD})(?!\w))?"
)
#: a Markdown link or reference definition whose target is the spec
MD_LINK = re.compile(rf"\[(?P<text>[^\]\n]*)\]\((?P<target>{PATH})\)")
MD_DEF = re.compile(rf"^(?P<head>[ \t]*\[[^\]\n]+\]:[ \t]*)(?P<target>{PATH})", re.M)
HEADING = re.compile(r"^#{1,6}[ \t]+(?P<title>.+?)[ \t]*#*[ \t]*$", re.M)
FENCE = re.compile(r"^[ \t]*(`{3,}|~{3,})")
SHORT = {"sec.": "section", "secs.": "sections", "§": "section"}
REMAINING = re.compile(rf"{_SPEC}|{re.escape(SPEC_DIR)}")


def slug(title: str) -> str:
    """GitHub's (and mkdocs') anchor of a heading made of words, digits and spaces."""
    title = re.sub(r"[`*_]|\[([^\]]*)\]\([^)]*\)", lambda m: m.group(1) or "", title)
    return re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")


def read_anchors(model_path: str) -> dict[str, str]:
    """Section number ("4", "4.2") -> anchor, from the numbered headings of the page."""
    text = open(model_path, encoding="utf-8").read()
    anchors = {}
    for m in HEADING.finditer(strip_fenced(text)):
        number = re.match(r"(\d+(?:\.\d+)*)\.?\s", m.group("title"))
        if number:
            anchors.setdefault(number.group(1), slug(m.group("title")))
    return anchors


def strip_fenced(text: str) -> str:
    """The text with fenced code blocks blanked (line count kept)."""
    out, fence = [], None
    for line in text.split("\n"):
        m = FENCE.match(line)
        if fence is None and m:
            fence = m.group(1)[0] * 3
            out.append("")
        elif fence is not None:
            if line.strip().startswith(fence):
                fence = None
            out.append("")
        else:
            out.append(line)
    return "\n".join(out)


def code_spans(text: str) -> list[tuple[int, int]]:
    """(start, end) of fenced blocks and inline code spans of a Markdown text."""
    spans, pos, fence, start = [], 0, None, 0
    for line in text.splitlines(keepends=True):
        m = FENCE.match(line)
        if fence is None and m:
            fence, start = m.group(1)[0] * 3, pos
        elif fence is not None and line.strip().startswith(fence):
            spans.append((start, pos + len(line)))
            fence = None
        pos += len(line)
    if fence is not None:
        spans.append((start, len(text)))
    for m in re.finditer(r"(?<!`)(`+)(?!`)(.+?)(?<!`)\1(?!`)", text, re.S):
        if not any(a <= m.start() < b for a, b in spans):
            spans.append((m.start(), m.end()))
    return spans


class Rewriter:
    def __init__(self, root: str, model_rel: str):
        self.root = root
        self.model_rel = model_rel.replace(os.sep, "/")
        self.model_path = os.path.join(root, model_rel)
        self.anchors = read_anchors(self.model_path)
        self.warnings: list[str] = []

    def anchor(self, number: str, where: str) -> str:
        """The anchor of section ``number``, or of its nearest parent that exists."""
        parts = number.split(".")
        while parts:
            key = ".".join(parts)
            if key in self.anchors:
                if key != number:
                    self.warnings.append(f"{where}: section {number} not in the model page; "
                                         f"linked to section {key}")
                return "#" + self.anchors[key]
            parts.pop()
        self.warnings.append(f"{where}: section {number} not in the model page; linked to "
                             "the page")
        return ""

    def old_anchor(self, path: str, where: str) -> str:
        """An anchor of the old page ("#4-forcing") as the new page's anchor."""
        if "#" not in path:
            return ""
        number = re.match(r"(\d+)", path.split("#", 1)[1])
        return self.anchor(number.group(1), where) if number else ""

    # --- plain text (Python, TOML, code in Markdown) ------------------------------------
    def plain(self, m: re.Match, where: str) -> str:
        if m.group("bare"):
            return f"{self.model_rel}, section {m.group('bare')}"
        if m.group("kw"):
            kw = m.group("kw")
            kw = SHORT.get(kw.lower(), kw)
            ws = m.group("ws").lstrip(",") or " "
            return f"{self.model_rel},{ws}{kw}{m.group('ws2') or ' '}{m.group('nums')}"
        if m.group("okw"):  # the number is out of reach (e.g. in the next string literal)
            ows = m.group("ows").lstrip(",") or " "
            return f"{self.model_rel},{ows}{SHORT.get(m.group('okw').lower(), m.group('okw'))}"
        return self.model_rel

    # --- Markdown ---------------------------------------------------------------------
    def link(self, m: re.Match, rel: str, where: str) -> str:
        if m.group("bare"):
            return f"[model, section {m.group('bare')}]({rel}{self.anchor(m.group('bare'), where)})"
        if m.group("okw"):
            return f"[{self.model_rel}]({rel}){m.group('ows')}{m.group('okw')}"
        if not m.group("kw"):
            return f"[{self.model_rel}]({rel}{self.old_anchor(m.group('path'), where)})"
        kw, nums = m.group("kw"), m.group("nums")
        ws = m.group("ws").lstrip(",") or " "
        ws2 = m.group("ws2") or " "
        if kw.lower().startswith("eq"):
            return f"[model,{ws}{kw}{ws2}{nums}]({rel})"
        kw = SHORT.get(kw.lower(), kw)
        numbers = re.findall(NUM, nums)
        if len(numbers) == 1 and nums == numbers[0]:
            return f"[model,{ws}{kw}{ws2}{nums}]({rel}{self.anchor(nums, where)})"
        linked = re.sub(NUM, lambda n: f"[{n.group(0)}]({rel}{self.anchor(n.group(0), where)})",
                        nums)
        return f"[model]({rel}),{ws}{kw}{ws2}{linked}"

    def markdown(self, text: str, path: str) -> tuple[str, int]:
        rel = os.path.relpath(self.model_path, os.path.dirname(path)).replace(os.sep, "/")
        count = 0

        def target(m: re.Match) -> str:
            nonlocal count
            count += 1
            new = rel + self.old_anchor(m.group("target"), path)
            if "text" in m.groupdict():
                label = re.sub(PATH, self.model_rel, m.group("text"))
                return f"[{label}]({new})"
            return m.group("head") + new

        text = MD_LINK.sub(target, text)
        text = MD_DEF.sub(target, text)
        spans = code_spans(text)
        out, pos = [], 0
        for m in CITATION.finditer(text):
            # a link made above: its label keeps the page's path, already rewritten
            in_code = any(a <= m.start() < b for a, b in spans)
            out.append(text[pos:m.start()])
            out.append(self.plain(m, path) if in_code else self.link(m, rel, path))
            pos = m.end()
            count += 1
        out.append(text[pos:])
        return "".join(out), count

    def other(self, text: str, path: str) -> tuple[str, int]:
        count = 0

        def sub(m: re.Match) -> str:
            nonlocal count
            count += 1
            return self.plain(m, path)

        return CITATION.sub(sub, text), count

    def rewrite(self, path: str) -> tuple[str, str, int]:
        old = open(path, encoding="utf-8").read()
        if path.endswith(".md"):
            new, count = self.markdown(old, path)
        else:
            new, count = self.other(old, path)
        if path.endswith(".py") and new != old:
            compile(new, path, "exec")  # never write a file that no longer parses
        return old, new, count


def text_files(root: str, skip: set[str]):
    for folder, dirs, names in os.walk(root):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in SKIP_DIRS)
        for name in sorted(names):
            path = os.path.join(folder, name)
            if name.endswith(TEXT_SUFFIXES) and os.path.realpath(path) not in skip:
                yield path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("root", help="the repository (or any tree) to rewrite")
    ap.add_argument("--model", default="docs/model.md",
                    help="the model page, relative to ROOT (default: docs/model.md)")
    ap.add_argument("--check", action="store_true",
                    help="write nothing; exit 1 if anything would be rewritten")
    args = ap.parse_args(argv)
    root = os.path.abspath(args.root)
    try:
        rw = Rewriter(root, args.model)
    except OSError as e:
        print(f"model_refs: cannot read the model page: {e}", file=sys.stderr)
        return 2
    if not rw.anchors:
        print(f"model_refs: {rw.model_path} has no numbered headings", file=sys.stderr)
        return 2
    skip = {os.path.realpath(__file__), os.path.realpath(rw.model_path)}
    total, remaining = 0, []
    for path in text_files(root, skip):
        shown = os.path.relpath(path, root)
        try:
            old, new, count = rw.rewrite(path)
        except UnicodeDecodeError:
            continue
        except SyntaxError as e:
            remaining.append(f"{shown}: not rewritten, the result would not parse: {e}")
            continue
        if count:
            total += count
            print(f"{shown}: {count} reference(s) {'to rewrite' if args.check else 'rewritten'}")
            if not args.check:
                with open(path, "w", encoding="utf-8", newline="") as f:
                    f.write(new)
        for i, line in enumerate((old if args.check else new).split("\n"), 1):
            if REMAINING.search(line):
                remaining.append(f"{shown}:{i}: {line.strip()}")
    for w in rw.warnings:
        print(f"warning: {w}")
    print(f"{total} reference(s) {'to rewrite' if args.check else 'rewritten'}")
    if remaining and not (args.check and total):
        print(f"{len(remaining)} line(s) still refer to the external spec:")
        for r in remaining:
            print("  " + r)
    if args.check:
        return 1 if total or remaining else 0
    return 1 if remaining else 0


if __name__ == "__main__":
    sys.exit(main())
