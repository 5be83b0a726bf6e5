// Opening a file the user named for reading, or creating one the program owns: anything but
// a regular file (a FIFO, a device node, a directory, a socket) is refused before it is
// read or written. The open is non-blocking, so a FIFO does not wait for a peer that may
// never come; for a regular file that changes nothing, and the descriptor is switched back
// to blocking.
#pragma once

#include <sys/types.h>

#include "skyloc/platform/status.h"
#include "skyloc/platform/unique_fd.h"

namespace skyloc {

// "a FIFO", "a device node", "a directory", "a symbolic link", "a socket", else "not a
// regular file".
const char* FileKindName(mode_t mode);

// Opens `path` with `flags` (O_RDONLY, O_RDWR). Errors name the file as "`what` PATH"
// ("image 'a.png'", "route database a.db"): kInvalidArgument "... is a FIFO, not a
// regular file: name a regular file", or the errno of the failed open.
Status OpenRegularFile(const char* path, int flags, const char* what, UniqueFd* out);

// Creates `path` (or opens it when it exists) with `flags` (O_WRONLY | O_TRUNC, O_RDWR)
// and `mode`, without following a symbolic link there: a link is refused by the open
// (ELOOP), anything else but a regular file after it. Errors name the file as "`what`
// PATH" ("the route's lock file a.db.lock"): kInvalidArgument "... is a FIFO, not a
// regular file: `fix`", or the errno of the failed open.
Status CreateRegularFile(const char* path, int flags, mode_t mode, const char* what,
                         const char* fix, UniqueFd* out);

}  // namespace skyloc
