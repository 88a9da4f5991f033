#!/usr/bin/env python3
"""Checks DESIGN.md's "Who may include whom" on the source tree.

Layers, lowest first (DESIGN.md):
  core -> hankel, signal, spectral -> subspace, pem, adaptive, realization, reduce,
  validate -> family, diagnose, fem -> io -> apps, python

Rules checked, for every header and source of a family (include/sysid/<family>/
and src/<family>/) and for apps/ and python/:
  1. a file includes only its own layer and the layers below it;
  2. the families form no include cycle (within a layer too): the graph
     "family A has a file that includes a header of family B" is acyclic;
  3. nothing in include/ includes apps/ or a header that lives only in src/
     (those are not installed);
  4. diagnose reaches other families through their public headers, never their
     detail/ ones.

Usage: scripts/check-layering.py [ROOT]   (exit 0 when clean, 1 with one line per
violation naming the file, the line and the rule).
"""
import os
import re
import sys

LAYERS = [
    ["core"],
    ["hankel", "signal", "spectral"],
    ["subspace", "pem", "adaptive", "realization", "reduce", "validate"],
    ["family", "diagnose", "fem"],
    ["io"],
    ["apps", "python"],
]
LAYER_OF = {family: level for level, families in enumerate(LAYERS) for family in families}

# #include <sysid/pem/arx.hpp>, "sysid/pem/arx.hpp" (public headers) and, in src/,
# "pem/detail/x.hpp" (the internal headers beside the sources).
PUBLIC_INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]sysid/([a-z_]+)/([^>"]+)[>"]')
INTERNAL_INCLUDE = re.compile(r'^\s*#\s*include\s*"([a-z_]+)/([^"]+)"')
SOURCE_SUFFIXES = (".hpp", ".cpp", ".h", ".cc")


def files_of(root):
    """(path relative to root, family, is_public_header) of every file checked."""
    for top, public in (("include/sysid", True), ("src", False)):
        base = os.path.join(root, top)
        for dirpath, _, names in os.walk(base):
            for name in sorted(names):
                if not name.endswith(SOURCE_SUFFIXES):
                    continue
                rel = os.path.relpath(os.path.join(dirpath, name), root)
                parts = os.path.relpath(os.path.join(dirpath, name), base).split(os.sep)
                if len(parts) < 2:
                    # config.hpp-like files directly in include/sysid belong to no family.
                    yield rel, None, public
                else:
                    yield rel, parts[0], public
    for top in ("apps", "python"):
        for dirpath, _, names in os.walk(os.path.join(root, top)):
            for name in sorted(names):
                if name.endswith(SOURCE_SUFFIXES):
                    yield os.path.relpath(os.path.join(dirpath, name), root), top, False


def includes_of(root, rel):
    """(line number, family included, path inside the family, is internal) per include."""
    with open(os.path.join(root, rel), encoding="utf-8") as text:
        for number, line in enumerate(text, 1):
            match = PUBLIC_INCLUDE.match(line)
            if match:
                yield number, match.group(1), match.group(2), False
                continue
            match = INTERNAL_INCLUDE.match(line)
            if match and match.group(1) in LAYER_OF and os.path.isfile(
                    os.path.join(root, "src", match.group(1), match.group(2))):
                yield number, match.group(1), match.group(2), True


def find_cycle(graph):
    """One cycle of the directed graph (dict node -> set of nodes) as a list, or None."""
    state = {}
    stack = []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for successor in sorted(graph.get(node, ())):
            if state.get(successor) == "open":
                return stack[stack.index(successor):] + [successor]
            if successor not in state:
                cycle = visit(successor)
                if cycle:
                    return cycle
        stack.pop()
        state[node] = "done"
        return None

    for node in sorted(graph):
        if node not in state:
            cycle = visit(node)
            if cycle:
                return cycle
    return None


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(__file__), ".."))
    violations = []
    graph = {}
    witness = {}  # (from, to) -> "file:line" of one include that makes the edge
    checked = 0
    for rel, family, public in files_of(root):
        checked += 1
        for line, target, path, internal in includes_of(root, rel):
            where = f"{rel}:{line}"
            if target not in LAYER_OF:
                violations.append(f"{where}: includes sysid/{target}/{path}, a folder that is no "
                                  f"family of DESIGN.md's layers")
                continue
            if public and internal:
                violations.append(f"{where}: an installed header includes {target}/{path}, which "
                                  f"lives only in src/ and is not installed")
            if public and target == "apps":
                violations.append(f"{where}: a header in include/ includes apps/")
            if family is None or family == target:
                continue
            if LAYER_OF[target] > LAYER_OF[family]:
                violations.append(f"{where}: {family} (layer {LAYER_OF[family]}) includes "
                                  f"{target}/{path} from the higher layer {LAYER_OF[target]} "
                                  f"({', '.join(LAYERS[LAYER_OF[target]])}); move the shared "
                                  f"piece down a layer")
            if family == "diagnose" and (internal or "/detail/" in "/" + path):
                violations.append(f"{where}: diagnose includes {target}/{path}, a detail/ header "
                                  f"of another family; use its public header")
            graph.setdefault(family, set()).add(target)
            witness.setdefault((family, target), where)
    cycle = find_cycle(graph)
    if cycle:
        steps = [f"{a} -> {b} ({witness[(a, b)]})" for a, b in zip(cycle, cycle[1:])]
        violations.append("include cycle between families: " + "; ".join(steps))
    for violation in violations:
        print(violation)
    edges = sum(len(targets) for targets in graph.values())
    if violations:
        print(f"check-layering: {len(violations)} violation(s) in {checked} files", file=sys.stderr)
        return 1
    print(f"check-layering: {checked} files, {edges} include edges between families, "
          f"layers and acyclicity as DESIGN.md says")
    return 0


if __name__ == "__main__":
    sys.exit(main())
