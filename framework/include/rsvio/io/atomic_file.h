// Atomic file output: every file rsvio writes for a user (run outputs, reports, comparison tables) goes
// through here. The content is written to a temporary file in the same folder ("<name>.tmp-<pid>"),
// flushed and closed, and only then renamed over the final name (rename(2) is atomic on one file
// system). So a reader, or a run killed with SIGKILL at any moment, sees either the previous complete
// file or the new complete file, never a truncated one; a failed write leaves no temporary behind.
#pragma once
#include <functional>
#include <ostream>
#include <string>

namespace rsvio::io {

// Calls fill(out) on a stream to the temporary file, then renames it to `path`. Throws rsvio::Error
// naming `path` (and `what`, e.g. "report") when the file cannot be created, written or renamed; any
// exception from fill() propagates after the temporary is removed.
void writeFileAtomic(const std::string& path, const std::function<void(std::ostream&)>& fill,
                     const std::string& what = "file", bool binary = false);

// The temporary name writeFileAtomic uses for `path` in this process.
std::string atomicTempPath(const std::string& path);

}  // namespace rsvio::io
