/* The open-file handle's allocator and error state: every handle-level error goes through here, so
 * its text, the message callback and the poisoning rule live once. Calls nothing else in libtetpack. */
#include <stdio.h>
#include <string.h>

#include "internal_file.h"

void *tpki_file_alloc(const tpk_file *file, uint64_t size)
{
    if (size > SIZE_MAX)
        return NULL;
    return file->allocator.alloc(file->allocator.user, size ? (size_t)size : 1);
}

void tpki_file_free(const tpk_file *file, void *ptr)
{
    if (ptr)
        file->allocator.free(file->allocator.user, ptr);
}

static int poisons(tpk_result code)
{
    return code != TPK_OK && code != TPK_ERR_INVALID_ARGUMENT && code != TPK_ERR_NOT_FOUND &&
           code != TPK_ERR_OUT_OF_MEMORY && code != TPK_ERR_LIMIT;
}

/* Store and announce an error; poison only when asked and the code calls for it. */
static tpk_result report(tpk_file *file, tpk_result code, const char *text, int may_poison)
{
    pthread_mutex_lock(&file->lock);
    snprintf(file->error_text, sizeof file->error_text, "%s", text);
    pthread_mutex_unlock(&file->lock);
    if (may_poison && poisons(code))
        atomic_store(&file->poisoned, 1);
    if (file->message)
        file->message(file->message_user, code, text);
    return code;
}

tpk_result tpki_file_report(tpk_file *file, tpk_result code, const char *text)
{
    return report(file, code, text, 1);
}

tpk_result tpki_file_refuse(tpk_file *file, tpk_result code, const char *text)
{
    return report(file, code, text, 0);
}

tpk_result tpki_file_fail(tpk_file *file, tpk_result code, const char *fmt, ...)
{
    tpki_diag diag;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(diag.text, sizeof diag.text, fmt, ap);
    va_end(ap);
    return report(file, code, diag.text, 1);
}

tpk_result tpki_file_usable(tpk_file *file)
{
    if (!atomic_load(&file->poisoned))
        return TPK_OK;
    /* Keep the text of the error that poisoned the handle; only announce the refusal. */
    if (file->message)
        file->message(file->message_user, TPK_ERR_BAD_STATE, "handle refused: an earlier corruption error");
    return TPK_ERR_BAD_STATE;
}

/* Issue 10: the text was read without the lock report() holds while writing it, so a thread reading it
 * while another failed could see half of each message. The copy is taken under that lock into storage
 * of the calling thread, which no other thread writes. The lock is not part of the handle's value, so
 * taking it through a const handle is sound (every handle is allocated non-const by file_create). */
const char *tpk_error_text(const tpk_file *file)
{
    static _Thread_local char copy[TPK_ERROR_TEXT_SIZE];
    if (!file)
        return "";
    tpk_file *locked = (tpk_file *)file;
    pthread_mutex_lock(&locked->lock);
    memcpy(copy, file->error_text, sizeof copy);
    pthread_mutex_unlock(&locked->lock);
    return copy;
}
