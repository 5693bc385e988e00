"""Damaged .tpk files for the fault suite (faults.py): corruption behind valid checksums (chunk bytes,
header and directory fields, offsets, memory and zstd bombs, extra zstd frames), plain flips and cuts."""
import random

import tpk_bytes

ABSURD_U64 = (0, 1, 63, 65, 0xFFFFFFFF, 0x7FFFFFFF, 1 << 40, 1 << 63, (1 << 64) - 1)


def tpk_mutations(original, seed):
    """[(name, bytes, must_refuse)]: chunk bytes flipped (plain: in place; zstd: in the frame, or in the
    decoded bytes and compressed again) and header or directory fields set to absurd values, every
    checksum recomputed; bad offsets, memory and zstd bombs, extra zstd frames; plain flips and cuts."""
    rng = random.Random(seed)
    out = []
    base = tpk_bytes.Tpk(original)
    size = len(original)

    def fresh():
        return tpk_bytes.Tpk(original)
    for k in range(6):
        t = fresh()
        e = rng.choice(t.entries)
        for _ in range(1 + k % 3):
            t.data[e["offset"] + rng.randrange(max(1, e["stored_size"]))] ^= rng.randrange(1, 256)
        out.append(("chunk_flip%d_%s" % (k, tag_name(e)), t.seal(), False))
    zstd_entries = [i for i, e in enumerate(base.entries) if e["codec"] == tpk_bytes.CODEC_ZSTD]
    for k in range(4 if zstd_entries else 0):
        t = fresh()
        e = t.entries[rng.choice(zstd_entries)]
        raw = bytearray(t.decoded(e))
        for _ in range(1 + k % 3):
            raw[rng.randrange(len(raw))] ^= rng.randrange(1, 256)
        frame = tpk_bytes.zstd_compress(raw, 3)
        if len(frame) <= e["stored_size"]:
            set_stored(t, e, frame)
            out.append(("zstd_raw_flip%d_%s" % (k, tag_name(e)), t.seal(), False))
    for k in range(8):
        t = fresh()
        field = rng.choice(("vertex_count", "tet_count", "shell_face_count", "chunk_count",
                            "directory_offset", "file_size", "ox", "maxz", "flags", "version_minor"))
        value = rng.choice(ABSURD_U64) if field not in ("ox", "maxz") else rng.choice(
            (float("nan"), float("inf"), -1e308))
        if field == "flags":
            value &= 0xFFFFFFFF
        if field == "version_minor":
            value &= 0xFFFF
        t.header[field] = value
        out.append(("header_%s_%s" % (field, value), t.seal(), False))
    for k in range(12):
        t = fresh()
        e = rng.choice(t.entries)
        field = rng.choice(("elem_count", "offset", "stored_size", "raw_size", "elem_size", "elem_type",
                            "codec", "index", "step", "tag"))
        value = rng.choice(ABSURD_U64)
        e[field] = value & {"elem_type": 0xFF, "codec": 0xFF, "elem_size": 0xFFFFFFFF, "index": 0xFFFFFFFF,
                            "step": 0xFFFFFFFF, "tag": 0xFFFFFFFF}.get(field, (1 << 64) - 1)
        out.append(("entry_%s_%s_%d" % (tag_name(e), field, value), t.seal(), False))
    out += offset_faults(fresh, rng)
    out += bomb_faults(fresh, base, zstd_entries)
    for k in range(3):
        flipped = bytearray(original)
        flipped[rng.randrange(size)] ^= rng.randrange(1, 256)
        out.append(("plain_flip%d" % k, bytes(flipped), False))
    for cut in (0, 100, 191, 192, size // 2, size - 1):
        out.append(("cut_%d" % cut, original[:cut], True))
    return out


def tag_name(e):
    return e["tag"].to_bytes(4, "little").decode("latin-1").strip("\0") or "0"


def set_stored(t, e, stored):
    """Replace an entry's stored bytes in place (they must fit in the old space; the rest is zeroed)."""
    at, room = e["offset"], e["stored_size"]
    t.data[at:at + room] = stored + bytes(room - len(stored))
    e["stored_size"] = len(stored)


def offset_faults(fresh, rng):
    """Offsets a compliant reader must refuse (spec §4): misaligned, past the end, onto another chunk,
    onto the directory, and sizes that run past the end; every checksum recomputed."""
    out = []
    cases = (("misaligned", lambda t, e: e["offset"] + 8), ("past_end", lambda t, e: len(t.data) + 64),
             ("huge", lambda t, e: (1 << 63) - 64), ("onto_other", lambda t, e: t.entries[0]["offset"]
                                                      if e is not t.entries[0] else t.entries[1]["offset"]),
             ("onto_directory", lambda t, e: t.header["directory_offset"]), ("into_header", lambda t, e: 64))
    for name, where in cases:
        t = fresh()
        e = rng.choice(t.entries)
        e["offset"] = where(t, e)
        out.append(("offset_%s_%s" % (name, tag_name(e)), t.seal(), True))
    t = fresh()
    e = t.entries[-1]
    e["stored_size"] = len(t.data)
    out.append(("stored_past_end_%s" % tag_name(e), t.seal(chunk_checksums=False), True))
    return out


def bomb_faults(fresh, base, zstd_entries):
    """Counts that claim gigabytes (consistent with each other, so only a limit or the file size stops
    them) and zstd frames that decode to far more than the entry says, or carry a second frame."""
    out = []
    for i, e in enumerate(base.entries[:4]):
        t = fresh()
        e = t.entries[i]
        e["elem_count"] = (1 << 40) // max(1, e["elem_size"])
        e["raw_size"] = e["elem_count"] * e["elem_size"]
        if e["codec"] == tpk_bytes.CODEC_NONE:
            e["stored_size"] = e["raw_size"]
        out.append(("memory_bomb_%s" % tag_name(e), t.seal(chunk_checksums=False), True))
    t = fresh()
    t.header["vertex_count"] = t.header["tet_count"] = 0x7FFFFFFF
    out.append(("memory_bomb_header_counts", t.seal(), True))
    for i in zstd_entries[:3]:
        e = base.entries[i]
        blocks = (e["stored_size"] - 14) // 4  # magic, header with a content size, 4 bytes a block
        if blocks < 2:
            continue
        for claim in (None, e["raw_size"], 1 << 60):
            t = fresh()
            set_stored(t, t.entries[i], tpk_bytes.rle_bomb(blocks, claim))
            out.append(("zstd_bomb_%s_claims_%s" % (tag_name(e), claim), t.seal(), True))
        raw = base.decoded(e)
        frame = tpk_bytes.zstd_compress(raw, 19)
        extras = (("skippable_after", frame + tpk_bytes.skippable_frame()),
                  ("skippable_before", tpk_bytes.skippable_frame() + frame),
                  ("two_frames", tpk_bytes.zstd_compress(raw[:len(raw) // 2], 19) +
                   tpk_bytes.zstd_compress(raw[len(raw) // 2:], 19)))
        for name, stored in extras:
            if len(stored) <= e["stored_size"]:
                t = fresh()
                set_stored(t, t.entries[i], stored)
                out.append(("zstd_%s_%s" % (name, tag_name(e)), t.seal(), True))
    return out
