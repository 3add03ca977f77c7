// Files the PC writes in place (a disk image as the SD card, an appended CSV, a block device),
// and the process's file size limit (issue 34). Host only.
//
//  * lock_for_writing(): an advisory exclusive lock (flock) held while the file is written,
//    so two processes never write one file at once: two seqslam-firmware runs on one card,
//    `seqslam config write` while the firmware runs, two sweeps appending to one CSV. The
//    second is refused before it writes anything. Locks are advisory: they stop the seqslam
//    tools, not a `dd` or an editor.
//  * ignore_file_size_signal(): SIGXFSZ ignored, so a write beyond the file size limit
//    (`ulimit -f`) fails with EFBIG ("File too large") and is reported like a full disk,
//    instead of killing the process with no message (and its temporary file left behind).
//  * check_file_size_limit(): whether writing up to a byte offset is within that limit, so a
//    file edited in place (a card) can be refused before the first write rather than left
//    half written.
#pragma once

#include <stdint.h>

#include <string>

namespace seqslam::hal {

// Takes an exclusive advisory lock on the open descriptor `fd` of `path` without waiting.
// Regular files and block devices are locked; character devices and FIFOs are not (a
// terminal or /dev/full is no one's card). The lock lasts until the descriptor is closed.
// Returns "" (locked, or the file system has no locks), or "PATH: in use by another process
// (...)" when another process holds the lock.
std::string lock_for_writing(int fd, const std::string& path);

// Sets SIGXFSZ to be ignored unless the process has its own handler. Idempotent.
void ignore_file_size_signal();

// The file size limit (RLIMIT_FSIZE) in bytes; UINT64_MAX when there is none.
uint64_t file_size_limit();

// "" when bytes [0, end) of a file can be written under the file size limit; else
// "PATH: the file size limit (ulimit -f) is N bytes, and writing it needs M: File too large".
std::string check_file_size_limit(const std::string& path, uint64_t end);

}  // namespace seqslam::hal
