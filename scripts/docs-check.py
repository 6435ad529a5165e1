#!/usr/bin/python3
"""Checks that every relative link and #anchor in README.md, CONTRIBUTING.md and docs/ resolves.

    scripts/docs-check.py [ROOT]        (ROOT: the repository, default: this script's parent)

A link [text](target) or ![alt](target) whose target is not a URL must name an existing file
or folder, relative to the page; a #fragment on a Markdown target (or on the page itself) must
be the anchor GitHub makes for one of its headings: the heading's text in lower case, every
character that is not a letter, digit, space, '-' or '_' dropped, spaces turned into '-', and a
'-1', '-2', ... suffix for the second, third, ... heading with the same anchor. Links inside
fenced code blocks and inline code are not links. Prints one line per broken link,
`file:line: reason`, and exits 1 if there is any; standard library only.
"""
import os
import re
import sys
import urllib.parse

LINK = re.compile(r"!?\[((?:[^\[\]]|\[[^\]]*\])*)\]\(\s*<?([^()\s>]*(?:\([^()\s]*\)[^()\s>]*)*)>?(?:\s+\"[^\"]*\")?\s*\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s*(```|~~~)")
HTML_ANCHOR = re.compile(r"<a\s+(?:name|id)=\"([^\"]+)\"")


def strip_inline_code(line):
    return re.sub(r"(`+)(.+?)\1", "", line)


def heading_text(raw):
    """The text GitHub renders for a heading: links and images to their text, code spans and
    emphasis to their content, HTML tags dropped."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", raw)
    text = re.sub(r"(`+)(.+?)\1", r"\2", text)
    text = re.sub(r"<[^>]+>", "", text)
    text = re.sub(r"(\*\*|__|\*|(?<!\w)_(?=\S)|(?<=\S)_(?!\w))", "", text)
    return text


def slug(text):
    text = heading_text(text).strip().lower()
    text = "".join(c for c in text if c.isalnum() or c in " -_")
    return text.replace(" ", "-")


def lines_outside_code(path):
    in_fence = False
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if FENCE.match(line):
                in_fence = not in_fence
                continue
            if not in_fence:
                yield number, line


_anchor_cache = {}


def anchors(path):
    if path not in _anchor_cache:
        seen, result = {}, set()
        for _, line in lines_outside_code(path):
            for name in HTML_ANCHOR.findall(line):
                result.add(name)
            m = HEADING.match(line)
            if not m:
                continue
            base = slug(m.group(2))
            count = seen.get(base, 0)
            seen[base] = count + 1
            result.add(base if count == 0 else "%s-%d" % (base, count))
        _anchor_cache[path] = result
    return _anchor_cache[path]


def pages(root):
    for name in ("README.md", "CONTRIBUTING.md"):
        if os.path.exists(os.path.join(root, name)):
            yield os.path.join(root, name)
    for folder, dirs, files in os.walk(os.path.join(root, "docs")):
        dirs.sort()
        for name in sorted(files):
            if name.endswith(".md"):
                yield os.path.join(folder, name)


def check(root):
    problems = []
    for page in pages(root):
        rel_page = os.path.relpath(page, root)
        for number, line in lines_outside_code(page):
            for m in LINK.finditer(strip_inline_code(line)):
                target = m.group(2)
                if not target or re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):
                    continue  # a URL (http:, https:, mailto:)
                path_part, _, fragment = target.partition("#")
                path_part = urllib.parse.unquote(path_part)
                if path_part:
                    if path_part.startswith("/"):
                        problems.append("%s:%d: %s: an absolute path" % (rel_page, number, target))
                        continue
                    resolved = os.path.normpath(os.path.join(os.path.dirname(page), path_part))
                    if os.path.relpath(resolved, root).split(os.sep)[0] == "..":
                        problems.append("%s:%d: %s: outside the repository" % (rel_page, number, target))
                        continue
                    if not os.path.exists(resolved):
                        problems.append("%s:%d: %s: no such file" % (rel_page, number, target))
                        continue
                else:
                    resolved = page
                if fragment:
                    if not resolved.endswith(".md") or os.path.isdir(resolved):
                        continue
                    fragment = urllib.parse.unquote(fragment)
                    if fragment not in anchors(resolved):
                        problems.append("%s:%d: %s: no heading with anchor #%s in %s" % (
                            rel_page, number, target, fragment, os.path.relpath(resolved, root)))
    return problems


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    root = os.path.abspath(root)
    problems = check(root)
    for p in problems:
        print(p)
    if problems:
        print("docs-check: %d broken link(s)" % len(problems), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
