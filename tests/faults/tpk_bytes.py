"""Byte-level tools for the fault suite: the .tpk header and directory (spec/tetpack-format.md §3, §4),
XXH64 and zstd through the system libraries (the same libxxhash and libzstd the project links), so a
corruption can be hidden behind valid checksums the way tests/fuzz/fuzz_reader.c does it."""
import ctypes
import struct

_xxhash = ctypes.CDLL("libxxhash.so.0")
_xxhash.XXH64.restype = ctypes.c_uint64
_xxhash.XXH64.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_uint64]
_zstd = ctypes.CDLL("libzstd.so.1")
for _name in ("ZSTD_decompress", "ZSTD_compress", "ZSTD_compressBound", "ZSTD_isError"):
    getattr(_zstd, _name).restype = ctypes.c_size_t
_zstd.ZSTD_isError.restype = ctypes.c_uint

HEADER = struct.Struct("<8sHHIII QQQ QQQ Q 3d3d3d 32s Q")
ENTRY = struct.Struct("<IHBBII QQQQQ II")
HEADER_FIELDS = ("magic", "version_major", "version_minor", "header_size", "flags", "dir_entry_size",
                 "file_size", "directory_offset", "chunk_count", "vertex_count", "tet_count",
                 "shell_face_count", "directory_checksum", "ox", "oy", "oz", "minx", "miny", "minz",
                 "maxx", "maxy", "maxz", "reserved", "header_checksum")
ENTRY_FIELDS = ("tag", "flags", "codec", "elem_type", "elem_size", "index", "elem_count", "offset",
                "stored_size", "raw_size", "checksum", "step", "reserved")
CODEC_NONE, CODEC_ZSTD = 0, 1


def xxh64(data):
    return _xxhash.XXH64(bytes(data), len(data), 0)


def zstd_decompress(frame, capacity):
    """The decoded bytes, or None when the frame does not decode into `capacity` bytes."""
    if capacity > 1 << 28:
        return None
    dst = ctypes.create_string_buffer(max(capacity, 1))
    n = _zstd.ZSTD_decompress(dst, ctypes.c_size_t(capacity), bytes(frame), ctypes.c_size_t(len(frame)))
    return None if _zstd.ZSTD_isError(ctypes.c_size_t(n)) else dst.raw[:n]


def zstd_compress(data, level):
    bound = _zstd.ZSTD_compressBound(ctypes.c_size_t(len(data)))
    dst = ctypes.create_string_buffer(bound)
    n = _zstd.ZSTD_compress(dst, ctypes.c_size_t(bound), bytes(data), ctypes.c_size_t(len(data)), level)
    assert not _zstd.ZSTD_isError(ctypes.c_size_t(n))
    return dst.raw[:n]


def rle_bomb(blocks, content_size=None):
    """A zstd frame of `blocks` RLE blocks of 128 KiB zeros each (4 bytes per block on disk): a
    decompression bomb. `content_size` is what the frame header claims (None: no claim)."""
    if content_size is None:
        head = bytes([0x00, 0x38])                      # no content size, window 2^17 bytes
    else:
        head = bytes([0xC0, 0x38]) + struct.pack("<Q", content_size)  # 8-byte content size
    out = bytearray(struct.pack("<I", 0xFD2FB528) + head)
    for b in range(blocks):
        last = 1 if b == blocks - 1 else 0
        out += struct.pack("<I", last | (1 << 1) | ((128 << 10) << 3))[:3] + b"\0"
    return bytes(out)


def skippable_frame(payload=b"\0\0\0\0"):
    return struct.pack("<II", 0x184D2A50, len(payload)) + payload


class Tpk:
    """A .tpk file held as a bytearray with its header and directory decoded as dicts."""

    def __init__(self, data):
        self.data = bytearray(data)
        self.header = dict(zip(HEADER_FIELDS, HEADER.unpack_from(self.data, 0)))
        at = self.header["directory_offset"]
        self.entries = [dict(zip(ENTRY_FIELDS, ENTRY.unpack_from(self.data, at + 64 * i)))
                        for i in range(self.header["chunk_count"])]

    def decoded(self, e):
        stored = self.data[e["offset"]:e["offset"] + e["stored_size"]]
        return bytes(stored) if e["codec"] == CODEC_NONE else zstd_decompress(stored, e["raw_size"])

    def seal(self, chunk_checksums=True):
        """Write the entries and header back, recomputing every checksum that can be computed: a chunk's
        when its bytes decode to raw_size bytes, then the directory's, then the header's."""
        at = self.header["directory_offset"]
        for i, e in enumerate(self.entries):
            if chunk_checksums and e["offset"] + e["stored_size"] <= len(self.data):
                raw = self.decoded(e)
                if raw is not None and len(raw) == e["raw_size"]:
                    e["checksum"] = xxh64(raw)
            if at + 64 * (i + 1) <= len(self.data):
                ENTRY.pack_into(self.data, at + 64 * i, *[e[f] for f in ENTRY_FIELDS])
        n = self.header["chunk_count"]
        if at <= len(self.data) and n <= (len(self.data) - at) // 64:
            self.header["directory_checksum"] = xxh64(self.data[at:at + 64 * n])
        HEADER.pack_into(self.data, 0, *[self.header[f] for f in HEADER_FIELDS])
        self.header["header_checksum"] = xxh64(self.data[:184])
        HEADER.pack_into(self.data, 0, *[self.header[f] for f in HEADER_FIELDS])
        return bytes(self.data)
