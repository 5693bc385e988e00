#!/usr/bin/env python3
"""What `tetpack extract` promises, read from the bytes of both files (the container through
tests/faults/tpk_bytes.py, chunks uncompressed or zstd):
  - fewer tets; TMAP and VMAP present, every value one the source has, and each kept vertex at the
    position of a source vertex with the same VMAP id (picks still name source cells and points);
  - the shell closed and consistently oriented: every directed edge a->b of a shell face is matched by
    as many b->a;
  - with a Tet32 layout in both files and a clip box: the kept tets are exactly the source's tets whose
    bounding box meets the box (as many, with the same TMAP ids).
usage: extract_check.py SOURCE.tpk EXTRACTED.tpk [x0,y0,z0,x1,y1,z1]"""
import collections
import os
import struct
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "faults"))
import tpk_bytes  # noqa: E402


def load(path):
    data = open(path, "rb").read()
    h = dict(zip(tpk_bytes.HEADER_FIELDS, tpk_bytes.HEADER.unpack_from(data, 0)))
    chunks = {}
    for i in range(h["chunk_count"]):
        e = dict(zip(tpk_bytes.ENTRY_FIELDS, tpk_bytes.ENTRY.unpack_from(data, h["directory_offset"] + i * tpk_bytes.ENTRY.size)))
        raw = data[e["offset"]:e["offset"] + e["stored_size"]]
        if e["codec"] == tpk_bytes.CODEC_ZSTD:
            raw = tpk_bytes.zstd_decompress(raw, e["raw_size"])
        chunks[(struct.pack("<I", e["tag"]).decode(), e["index"], e["step"])] = raw
    return h, chunks


def ints(raw):
    return struct.unpack("<%di" % (len(raw) // 4), raw)


def positions(h, chunks):
    p = struct.unpack("<%df" % (len(chunks[("POS3", 0, 0)]) // 4), chunks[("POS3", 0, 0)])
    o = (h["ox"], h["oy"], h["oz"])
    return [tuple(o[k] + p[3 * i + k] for k in range(3)) for i in range(len(p) // 3)]


def tets32(chunks):
    r = ints(chunks[("TT32", 0, 0)])
    out = []
    for t in range(len(r) // 8):
        v0, v1, v2, vx = r[8 * t:8 * t + 4]
        out.append((v0, v1, v2, vx ^ v0 ^ v1 ^ v2))
    return out


def meets(box, pos, tet):
    for k in range(3):
        xs = [pos[v][k] for v in tet]
        if max(xs) < box[k] or min(xs) > box[k + 3]:
            return False
    return True


def fail(msg):
    sys.exit("extract_check: " + msg)


def main():
    hs, cs = load(sys.argv[1])
    he, ce = load(sys.argv[2])
    box = [float(x) for x in sys.argv[3].split(",")] if len(sys.argv) > 3 else None
    if not he["tet_count"] < hs["tet_count"]:
        fail("%d tets kept of %d: not fewer" % (he["tet_count"], hs["tet_count"]))
    tmap_s, tmap_e = ints(cs[("TMAP", 0, 0)]), ints(ce[("TMAP", 0, 0)])
    vmap_s, vmap_e = ints(cs[("VMAP", 0, 0)]), ints(ce[("VMAP", 0, 0)])
    if len(tmap_e) != he["tet_count"] or len(vmap_e) != he["vertex_count"]:
        fail("TMAP/VMAP counts do not match the header")
    if not set(tmap_e) <= set(tmap_s):
        fail("TMAP names source cells the source file does not: %s" % sorted(set(tmap_e) - set(tmap_s))[:5])
    pos_s, pos_e = positions(hs, cs), positions(he, ce)
    at = collections.defaultdict(set)
    for v, src in enumerate(vmap_s):
        at[src].add(pos_s[v])
    for v, src in enumerate(vmap_e):
        if src not in at or pos_e[v] not in at[src]:
            fail("vertex %d (VMAP %d) is not at a position of source point %d" % (v, src, src))
    shell = ints(ce[("SHEL", 0, 0)])
    edges = collections.Counter()
    for f in range(len(shell) // 4):
        a, b, c = shell[4 * f:4 * f + 3]
        edges.update([(a, b), (b, c), (c, a)])
    open_edges = [e for e, n in edges.items() if edges[(e[1], e[0])] != n]
    if open_edges:
        fail("the shell is not closed: %d directed edges unmatched, first %s" % (len(open_edges), open_edges[0]))
    if box and ("TT32", 0, 0) in cs and ("TT32", 0, 0) in ce:
        kept = [t for t, tet in enumerate(tets32(cs)) if meets(box, pos_s, tet)]
        if len(kept) != he["tet_count"] or [tmap_s[t] for t in kept] != list(tmap_e):
            fail("%d source tets meet the box, %d kept" % (len(kept), he["tet_count"]))
        if not all(meets(box, pos_e, tet) for tet in tets32(ce)):
            fail("a kept tet does not meet the box")
    print("extract_check: %d of %d tets, %d shell faces, closed; TMAP/VMAP map into the source" %
          (he["tet_count"], hs["tet_count"], len(shell) // 4))


if __name__ == "__main__":
    main()
