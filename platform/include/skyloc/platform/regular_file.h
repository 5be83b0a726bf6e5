// Opening a file the user named for reading: anything but a regular file (a FIFO, a device
// node, a directory, a socket) is refused before it is read. The open is non-blocking, so
// a FIFO does not wait for a writer that may never come; for a regular file that changes
// nothing, and the descriptor is switched back to blocking.
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

}  // namespace skyloc
