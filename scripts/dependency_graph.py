#!/usr/bin/env python3
"""The project's library graph, from CMake itself (cmake --graphviz), as ARCHITECTURE.md shows it.

  scripts/dependency_graph.py                      print the graph (one line per target)
  scripts/dependency_graph.py --check ARCHITECTURE.md
                                                   exit 1 (with a diff) if the block between
                                                   <!-- dependency-graph --> and
                                                   <!-- /dependency-graph --> differs
  scripts/dependency_graph.py --write ARCHITECTURE.md   rewrite that block
  scripts/dependency_graph.py --dot out.dot        also keep the project-only graph for `dot`

Only the project's own targets (dpc*) and their direct links to each other are listed; third-party
libraries (Eigen, Fast DDS, Protobuf, …) are left out. Configures a throwaway build directory
(tests and benchmarks off), so it never touches the caller's build.
"""

import argparse
import difflib
import os
import re
import subprocess
import sys
import tempfile

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
BEGIN = "<!-- dependency-graph -->"
END = "<!-- /dependency-graph -->"


def graph(source):
    """{target: sorted direct project dependencies} from cmake --graphviz."""
    with tempfile.TemporaryDirectory(prefix="dpc-graph-") as build:
        dot = os.path.join(build, "graph.dot")
        subprocess.run(["cmake", "-S", source, "-B", build, "-DDPC_BUILD_TESTS=OFF",
                        "-DDPC_BUILD_BENCHMARKS=OFF", f"--graphviz={dot}"],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        text = open(dot, encoding="utf-8").read()
    labels = dict(re.findall(r'"(node\d+)" \[ label = "([^"]+)"', text))
    ours = {node: label for node, label in labels.items() if label.startswith("dpc")}
    edges = {label: set() for label in ours.values()}
    for source_node, target_node in re.findall(r'"(node\d+)" -> "(node\d+)"', text):
        if source_node in ours and target_node in ours:
            edges[ours[source_node]].add(ours[target_node])
    return {target: sorted(deps) for target, deps in edges.items()}


def render(edges):
    width = max(len(target) for target in edges)
    lines = [f"{target.ljust(width)}  → {', '.join(deps) if deps else '(third-party only)'}"
             for target, deps in sorted(edges.items())]
    return "```\n" + "\n".join(lines) + "\n```\n"


def block_of(text):
    start, end = text.find(BEGIN), text.find(END)
    if start < 0 or end < start:
        return None
    return text[start + len(BEGIN):end].strip("\n") + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--source", default=REPO)
    parser.add_argument("--check", metavar="MARKDOWN")
    parser.add_argument("--write", metavar="MARKDOWN")
    parser.add_argument("--dot", metavar="FILE")
    args = parser.parse_args()
    edges = graph(args.source)
    rendered = render(edges)
    if args.dot:
        with open(args.dot, "w", encoding="utf-8") as out:
            out.write("digraph dpc {\n  rankdir=LR;\n")
            for target, deps in sorted(edges.items()):
                for dep in deps:
                    out.write(f'  "{target}" -> "{dep}";\n')
            out.write("}\n")
    if args.write:
        text = open(args.write, encoding="utf-8").read()
        if block_of(text) is None:
            print(f"{args.write}: no {BEGIN} … {END} block", file=sys.stderr)
            return 2
        start, end = text.find(BEGIN) + len(BEGIN), text.find(END)
        with open(args.write, "w", encoding="utf-8") as out:
            out.write(text[:start] + "\n" + rendered + text[end:])
        return 0
    if args.check:
        documented = block_of(open(args.check, encoding="utf-8").read())
        if documented is None:
            print(f"{args.check}: no {BEGIN} … {END} block", file=sys.stderr)
            return 1
        if documented != rendered:
            diff = difflib.unified_diff(documented.splitlines(), rendered.splitlines(),
                                        "ARCHITECTURE.md", "cmake --graphviz", lineterm="")
            print("the library graph in ARCHITECTURE.md is not CMake's "
                  "(scripts/dependency_graph.py --write ARCHITECTURE.md):\n" + "\n".join(diff))
            return 1
        print("ARCHITECTURE.md's library graph is CMake's")
        return 0
    sys.stdout.write(rendered)
    return 0


if __name__ == "__main__":
    sys.exit(main())
