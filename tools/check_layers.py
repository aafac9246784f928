#!/usr/bin/env python3
"""Checks that the folders of src/ only include downwards.

CMakeLists.txt lists the folders of src/ in the order of the data flow
(set(VDBMARCH_LAYERS core parse ...)). A file in src/<layer>/ may include
headers of its own folder and of the folders before it, never of a later one,
and the include graph between folders must have no cycle.

Usage: check_layers.py [SOURCE_DIR]   (default: the folder above tools/)
Exit status 0 when the layering holds; 1 with one line per offence
("src/a/b.cpp:12: #include "x/y.h" (a includes later layer x)") otherwise;
2 when CMakeLists.txt has no VDBMARCH_LAYERS.
"""

import os
import re
import sys

SOURCE_SUFFIXES = (".h", ".hpp", ".cpp", ".cc", ".inl")
INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')
LAYERS_RE = re.compile(r"set\s*\(\s*VDBMARCH_LAYERS\s+([^)]*)\)", re.S)


def read_layers(root):
    with open(os.path.join(root, "CMakeLists.txt"), encoding="utf-8") as f:
        text = f.read()
    # Drop comments so a commented-out list is not taken.
    text = "\n".join(line.split("#", 1)[0] for line in text.splitlines())
    m = LAYERS_RE.search(text)
    if not m:
        return None
    return m.group(1).split()


def source_files(src, folder):
    for dirpath, _, names in os.walk(os.path.join(src, folder)):
        for name in sorted(names):
            if name.endswith(SOURCE_SUFFIXES):
                yield os.path.join(dirpath, name)


def includes(path):
    """(line number, included path) for every quoted include of a file."""
    out = []
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            m = INCLUDE_RE.match(line)
            if m:
                out.append((number, m.group(1)))
    return out


def find_cycle(graph):
    """A list of folders forming a cycle (first == last), or None."""
    white, grey, black = 0, 1, 2
    colour = {node: white for node in graph}
    stack = []

    def visit(node):
        colour[node] = grey
        stack.append(node)
        for nxt in sorted(graph[node]):
            if colour.get(nxt, black) == grey:
                return stack[stack.index(nxt):] + [nxt]
            if colour.get(nxt) == white:
                cycle = visit(nxt)
                if cycle:
                    return cycle
        stack.pop()
        colour[node] = black
        return None

    for node in sorted(graph):
        if colour[node] == white:
            cycle = visit(node)
            if cycle:
                return cycle
    return None


def main(argv):
    root = os.path.abspath(argv[1] if len(argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
    src = os.path.join(root, "src")
    layers = read_layers(root)
    if not layers:
        print("check_layers: no set(VDBMARCH_LAYERS ...) in %s" % os.path.join(root, "CMakeLists.txt"))
        return 2
    rank = {layer: i for i, layer in enumerate(layers)}
    folders = sorted(d for d in os.listdir(src) if os.path.isdir(os.path.join(src, d)))
    problems = []

    for folder in folders:
        if folder not in rank:
            problems.append("src/%s/: folder is not in VDBMARCH_LAYERS (%s)" % (folder, " ".join(layers)))

    graph = {folder: set() for folder in folders}
    for folder in folders:
        for path in source_files(src, folder):
            rel = os.path.relpath(path, root)
            for number, inc in includes(path):
                parts = inc.split("/")
                if len(parts) < 2 or parts[0] not in graph:
                    continue  # same-folder or third-party include
                target = parts[0]
                if target == folder:
                    continue
                graph[folder].add(target)
                if folder in rank and target in rank and rank[target] > rank[folder]:
                    problems.append('%s:%d: #include "%s" (%s includes the later layer %s)'
                                    % (rel, number, inc, folder, target))

    cycle = find_cycle(graph)
    if cycle:
        problems.append("include cycle between folders of src/: %s" % " -> ".join(cycle))

    for p in problems:
        print(p)
    if problems:
        print("check_layers: %d problem(s); layers in order: %s" % (len(problems), " ".join(layers)))
        return 1
    print("check_layers: %d folders, layers in order: %s" % (len(folders), " ".join(layers)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
