#!/usr/bin/env bash
# tetpack check on the generated corpus of broken meshes (tests/broken/make_broken.py): every check
# fires where it must with the exact count, and near misses stay silent.
source "$(dirname "$0")/common.sh"
$PY "$SRC/tests/broken/make_broken.py" "$WORK/corpus"
$PY "$SRC/tests/broken/run_corpus.py" "$TPK" "$WORK/corpus"
