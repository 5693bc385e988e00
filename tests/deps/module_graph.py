#!/usr/bin/env python3
"""The house rules, read from the built objects and the sources (docs/ARCHITECTURE.md, "Rules").

1. No call cycles between files: file A "uses" file B when A's object file references a symbol that
   B's object file defines (nm). Every strongly connected component of that graph must be one file.
   A module split over several files keeps its shared helpers in a private header and its entry
   file on top, calling down.
2. No .c/.cpp file directly in tools/: every source lives in the room of its stage.
3. A private header (*internal*.h) is included only by files in its own folder.
4. Folders in one order (FOLDER_ORDER below, the only place it is written): a file may include a header
   of, and use a symbol defined in, its own folder or a folder of a lower level, never one of its own
   level or above. Checked on the quoted #includes of format/, libtetpack/ and tools/, and on the
   objects of every binary (TARGETS, tetpack-mpi included).

usage: module_graph.py SOURCE_DIR BUILD_DIR [--dot]    exit 0 when every rule holds, 1 otherwise
       BUILD_DIR "-": the source rules only (2, 3, 4 on includes), for trees with no build
"""
import os
import re
import subprocess
import sys

TARGETS = ("tetpack", "tetpack_tools", "tetpack_cli", "tetpack_mpi")

# The folders, lowest first (docs/ARCHITECTURE.md §3). Folders on one level are siblings: neither may use
# the other. A folder of tools/ is named by its first component (import/vtk is import).
FOLDER_ORDER = (
    ("format",),
    ("libtetpack",),
    ("base",),
    ("mesh",),
    ("mesher",),
    ("import",),
    ("convert",),
    ("check", "export", "iso", "render"),
    ("render_vk", "scene"),
    ("extract", "view"),
    ("cli",),
    ("mpi",),
)
LEVEL = {room: level for level, rooms in enumerate(FOLDER_ORDER) for room in rooms}


def room_of(path):
    """The folder of FOLDER_ORDER a project file belongs to, or None (tests, bench, python)."""
    parts = path.split(os.sep)
    if parts[0] == "tools":
        return parts[1] if len(parts) > 2 else None
    return parts[0] if parts[0] in ("format", "libtetpack") else None


def order_problem(user, used, what):
    """A message when file `user` may not use file `used` under FOLDER_ORDER, else None."""
    a, b = room_of(user), room_of(used)
    if a is None or b is None or a == b:
        return None
    for room, path in ((a, user), (b, used)):
        if room not in LEVEL:
            return f"{path}: folder {room}/ is not in FOLDER_ORDER (tests/deps/module_graph.py); declare its level"
    if LEVEL[b] < LEVEL[a]:
        return None
    where = "the same level as" if LEVEL[b] == LEVEL[a] else "above"
    return f"{user}: {what} {used}, but {b}/ is {where} {a}/ in the folder order"


def objects(source_dir, build_dir):
    """(source path relative to the source dir, object path) for the library, tool and CLI targets;
    objects left in the build tree by sources since moved or deleted are skipped."""
    found = []
    for root, _dirs, files in os.walk(build_dir):
        parts = root.split(os.sep)
        target = next((p[:-4] for p in parts if p.endswith(".dir")), None)
        if target not in TARGETS:
            continue
        for name in files:
            if not name.endswith(".o"):
                continue
            obj = os.path.join(root, name)
            # <build>/<subdir>/CMakeFiles/<target>.dir/<path below subdir>.c.o
            below = root.split(target + ".dir", 1)[1].lstrip(os.sep)
            subdir = root.split(os.sep + "CMakeFiles" + os.sep, 1)[0]
            subdir = os.path.relpath(subdir, build_dir)
            src = os.path.normpath(os.path.join(subdir, below, name[:-2]))
            if os.path.isfile(os.path.join(source_dir, src)):
                found.append((src, obj))
    return sorted(found)


def symbols(obj):
    out = subprocess.run(["nm", "-P", obj], check=True, capture_output=True, text=True).stdout
    defined, used = set(), set()
    for line in out.splitlines():
        fields = line.split()
        if len(fields) < 2:
            continue
        name, kind = fields[0], fields[1]
        if kind == "U":
            used.add(name)
        elif kind in "TDBRVWGS" and kind.isupper():
            defined.add(name)
    return defined, used


def call_graph(objs):
    defs, uses = {}, {}
    owner = {}
    for src, obj in objs:
        d, u = symbols(obj)
        defs[src], uses[src] = d, u
        for name in d:
            owner.setdefault(name, src)
    graph = {src: set() for src, _ in objs}
    for src in graph:
        for name in uses[src]:
            other = owner.get(name)
            if other and other != src:
                graph[src].add(other)
    return graph


def strongly_connected(graph):
    index, low, stack, on_stack, result = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        # Iterative Tarjan: (node, iterator over its successors).
        work = [(v, iter(sorted(graph[v])))]
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        while work:
            node, succ = work[-1]
            advanced = False
            for w in succ:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    advanced = True
                    break
                if w in on_stack:
                    low[node] = min(low[node], index[w])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == node:
                        break
                result.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return result


INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def sources(source_dir, top):
    for root, _dirs, files in os.walk(os.path.join(source_dir, top)):
        for name in files:
            if name.endswith((".c", ".cpp", ".h")):
                yield os.path.relpath(os.path.join(root, name), source_dir)


def resolve(source_dir, including, name):
    """The project file a quoted include names: beside the including file, else under tools/ or libtetpack/."""
    for base in (os.path.dirname(including), "tools", "libtetpack", "format"):
        cand = os.path.normpath(os.path.join(base, name))
        if os.path.isfile(os.path.join(source_dir, cand)):
            return cand
    return None


def include_problems(source_dir):
    problems = []
    files = [rel for top in ("format", "libtetpack", "tools") for rel in sources(source_dir, top)]
    for rel in sorted(files):
        if os.path.dirname(rel) == "tools" and rel.endswith((".c", ".cpp")):
            problems.append(f"{rel}: a source file directly in tools/; move it into the room of its stage")
        with open(os.path.join(source_dir, rel), encoding="utf-8", errors="replace") as f:
            text = f.read()
        for name in INCLUDE.findall(text):
            target = resolve(source_dir, rel, name)
            if not target:
                continue
            order = order_problem(rel, target, f'includes "{name}", from')
            if order:
                problems.append(order)
            if not target.startswith("tools" + os.sep):
                continue
            same_room = os.path.dirname(target) == os.path.dirname(rel)
            if "internal" in os.path.basename(target) and not same_room:
                problems.append(f'{rel}: includes "{name}", a private header of {os.path.dirname(target)}/')
    return problems


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    source_dir, build_dir = argv[1], argv[2]
    if build_dir == "-":
        problems = include_problems(source_dir)
        for p in problems:
            print(p)
        print(f"module_graph: sources only, {len(problems)} placement problems")
        return 1 if problems else 0
    objs = objects(source_dir, build_dir)
    if not objs:
        print(f"module_graph: no object files of {', '.join(TARGETS)} under {build_dir}", file=sys.stderr)
        return 2
    graph = call_graph(objs)
    if "--dot" in argv:
        print("digraph tetpack {")
        for src in sorted(graph):
            for dst in sorted(graph[src]):
                print(f'  "{src}" -> "{dst}";')
        print("}")
        return 0
    cycles = [c for c in strongly_connected(graph) if len(c) > 1]
    problems = include_problems(source_dir)
    for src in sorted(graph):
        for dst in sorted(graph[src]):
            order = order_problem(src, dst, "uses a symbol of")
            if order:
                problems.append(order)
    for comp in cycles:
        edges = [f"{a} -> {b}" for a in comp for b in sorted(graph[a]) if b in comp]
        problems.append("call cycle between " + ", ".join(comp) + ":\n    " + "\n    ".join(edges))
    for p in problems:
        print(p)
    print(f"module_graph: {len(objs)} files, {sum(len(v) for v in graph.values())} uses between files, "
          f"{len(cycles)} call cycles, {len(problems) - len(cycles)} placement problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
