// Reading HDF5 files we did not write. Debian's libhdf5 1.10.8 crashes on crafted files
// (SIGFPE in H5Dopen2, SIGSEGV in H5Dread, a heap overflow in H5Aexists) and can allocate
// without bound before any check of ours runs, and what it does inside cannot be checked
// from outside. So a file is first read completely in a child process with an address-space
// limit and a time limit; only when the child finishes (or fails with an ordinary error,
// which the real read then reports in full) does the process read it itself. A crash, a
// sanitizer report, the memory limit or the time limit in the child becomes a FormatError
// naming the file. A file that passed is remembered (path, size, modification time) so a
// trainer reopening its recordings pays once.
#pragma once
#include <functional>
#include <string>

namespace yelan::camera {

struct UntrustedLimits {
  unsigned long long memory_bytes = 4ull << 30;  // the child's address space beyond the caller's (not under ASan)
  unsigned seconds = 120;                        // the child's CPU time
};

// Runs `read_all` (a complete read of `path`, results discarded) in a child first, unless
// this file already passed or we are that child. Throws FormatError when the child died.
void vet_in_child(const std::string& path, const std::function<void()>& read_all, const UntrustedLimits& limits = {});

// Forgets which files passed (a fuzzer rewrites one scratch file faster than its
// modification time moves).
void forget_vetted_files();

// True inside the vetting child (nested readers skip vetting there).
bool vetting_child();

}  // namespace yelan::camera
