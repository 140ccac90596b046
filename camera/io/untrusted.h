// Reading HDF5 files we did not write. Debian's libhdf5 1.10.8 crashes on crafted files
// (SIGFPE in H5Dopen2, SIGSEGV in H5Dread, a heap overflow in H5Aexists) and can allocate
// without bound before any check of ours runs, and what it does inside cannot be checked
// from outside. So a file is first read completely in a child process with an address-space
// limit and a time limit; only when the child finishes (or fails with an ordinary error,
// which the real read then reports in full, unless the child's resident memory grew by more
// than max(512 MiB, 16x the file's size) first: libhdf5 sizes a variable-length string by
// its stored length, so a 10 kB file can take 2 GB to refuse, and not twice) does the
// process read it itself. A crash, a sanitizer report, the memory limit or the time limit
// in the child becomes a FormatError naming the file. A file that passed is remembered
// (device, inode, size, modification and status-change times) so a trainer reopening its
// recordings pays once; and, across processes, in a cache file (see use_vet_cache()), so a
// training or an evaluation over a dataset of hundreds of recordings does not read every
// file twice each time it starts.
#pragma once
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace yelan::camera {

struct UntrustedLimits {
  unsigned long long memory_bytes = 4ull << 30;  // the child's address space beyond the caller's (not under ASan)
  unsigned seconds = 120;                        // the child's CPU time
};

// Runs `read_all` (a complete read of `path`, results discarded) in a child first, unless
// this file already passed or we are that child. Throws FormatError when the child died.
void vet_in_child(const std::string& path, const std::function<void()>& read_all, const UntrustedLimits& limits = {});

// Vets many files before the caller opens them, `jobs` children at a time; files that
// already passed cost nothing. For a caller about to read hundreds of files (a training's
// recordings) while it is still small: a child forked from a training's gigabytes starts
// slowly (every page it touches turns copy-on-write, ~1.4 s a recording), one forked before
// the networks are allocated does not. Returns how many children ran. When files fail,
// throws the FormatError of the first of them in `paths` order, after every child ended.
std::size_t vet_all_in_children(const std::vector<std::string>& paths,
                                const std::function<void(const std::string&)>& read_all, int jobs,
                                const UntrustedLimits& limits = {});

// Forgets which files passed, the cache file's entries included, for the rest of the
// process (a fuzzer rewrites one scratch file faster than its modification time moves).
void forget_vetted_files();

// The cache of files that passed, shared by every process of the user: YELAN_VET_CACHE
// (a path, or "off"), else $XDG_CACHE_HOME/yelan/vetted-files, else ~/.cache/yelan/vetted-files.
// A file goes in only when its status has not changed for 2 s before it was read
// (status-change times are coarse), and any change to it (contents, size, times, a new
// file at the path) makes it a stranger again.
// use_vet_cache: `path` is the cache file from now on ("" for none), forgetting what passed
// so far; for tests and tools that must not share the user's cache.
void use_vet_cache(const std::string& path);

// True inside the vetting child (nested readers skip vetting there).
bool vetting_child();

}  // namespace yelan::camera
