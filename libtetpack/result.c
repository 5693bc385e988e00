/* English names of tpk_result codes. */
#include "tetpack.h"

const char *tpk_result_string(tpk_result result)
{
    switch (result) {
    case TPK_OK: return "ok";
    case TPK_ERR_INVALID_ARGUMENT: return "invalid argument";
    case TPK_ERR_IO: return "I/O error";
    case TPK_ERR_OUT_OF_MEMORY: return "out of memory";
    case TPK_ERR_NOT_TETPACK: return "not a tetpack file (bad magic)";
    case TPK_ERR_TRUNCATED: return "file is truncated";
    case TPK_ERR_VERSION: return "unsupported (newer) major version";
    case TPK_ERR_HEADER_CHECKSUM: return "header checksum mismatch";
    case TPK_ERR_DIRECTORY_CHECKSUM: return "chunk directory checksum mismatch";
    case TPK_ERR_CHUNK_CHECKSUM: return "chunk checksum mismatch";
    case TPK_ERR_UNSUPPORTED_CHUNK: return "unknown required chunk or codec";
    case TPK_ERR_OUT_OF_BOUNDS: return "offset or size past the end of the file";
    case TPK_ERR_OVERLAP: return "overlapping chunks";
    case TPK_ERR_MISALIGNED: return "misaligned chunk";
    case TPK_ERR_CORRUPT: return "corrupt file";
    case TPK_ERR_LIMIT: return "limit exceeded";
    case TPK_ERR_NOT_FOUND: return "not found";
    case TPK_ERR_DECOMPRESS: return "decompression failed";
    case TPK_ERR_BAD_STATE: return "handle unusable after an earlier corruption error";
    case TPK_ERR_MESH: return "inconsistent mesh connectivity";
    case TPK_RESULT_COUNT: break;
    }
    return "unknown result code";
}
