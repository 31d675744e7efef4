#!/usr/bin/python3
"""Checks the library picture of docs/architecture.md (its first mermaid block) against the build.

Usage: check_architecture.py ARCHITECTURE_MD LIBRARY_LINKS_TXT
LIBRARY_LINKS_TXT has one line per library: its concern name, a space, its LINK_LIBRARIES (';'-separated), as
tests/docs/CMakeLists.txt generates it. The picture passes when
  - it draws exactly the libraries of the build (the concerns, msgs, bench and cli),
  - every arrow it draws is a link the build has (no invented dependency),
  - every link the build has is reachable along its arrows (arrows to common are implied, as the doc says).
Exit 0 when it passes, 1 with one line per problem otherwise.
"""
import re
import sys

# Generated message libraries the picture draws as one box.
PICTURE_NAME = {"ros2_msgs": "msgs"}


def picture(path):
    text = open(path, encoding="utf-8").read()
    block = re.search(r"```mermaid\n(.*?)```", text, re.S)
    if not block:
        sys.exit(f"{path}: no mermaid block")
    nodes, edges = set(), set()
    for line in block.group(1).splitlines():
        line = line.strip()
        edge = re.fullmatch(r"(\w+) --> (\w+)", line)
        if edge:
            edges.add(edge.groups())
            continue
        node = re.match(r"(\w+)(\[|$)", line)
        if node and node.group(1) != "flowchart":
            nodes.add(node.group(1))
    return nodes, edges


def build(path):
    links = {}
    for n, line in enumerate(open(path, encoding="utf-8"), 1):
        if not line.strip():
            continue
        name, _, deps = line.strip().partition(" ")
        found = set()
        for dep in deps.split(";"):
            m = re.fullmatch(r"faultline_(\w+)", dep.strip())
            if m:
                found.add(PICTURE_NAME.get(m.group(1), m.group(1)))
        found.discard(name)
        links[name] = found
    return links


def reachable(edges, start):
    seen, todo = set(), [start]
    while todo:
        a = todo.pop()
        for x, y in edges:
            if x == a and y not in seen:
                seen.add(y)
                todo.append(y)
    return seen


def main():
    doc, links_path = sys.argv[1], sys.argv[2]
    nodes, edges = picture(doc)
    links = build(links_path)
    problems = []
    expected = set(links) | {"msgs"}
    for name in sorted(expected - nodes):
        problems.append(f"{doc}: library {name} is built but not drawn")
    for name in sorted(nodes - expected):
        problems.append(f"{doc}: {name} is drawn but no such library is built")
    for a, b in sorted(edges):
        if b not in links.get(a, set()):
            problems.append(f"{doc}: arrow {a} --> {b}, but faultline_{a} does not link faultline_{b}")
    for a in sorted(links):
        missing = links[a] - reachable(edges, a) - {"common"}
        for b in sorted(missing):
            problems.append(f"{doc}: faultline_{a} links faultline_{b}, which no path of arrows from {a} reaches")
    for p in problems:
        print(p)
    print(f"check_architecture: {len(nodes)} libraries, {len(edges)} arrows, {sum(map(len, links.values()))} "
          f"links in the build, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
