"""Writing a file the one way yelan does (camera/io/temp_file.h, in C++): into a temporary
file beside the target, created exclusively under a random name (a link planted at a
predictable name is never followed), renamed over the target when complete and removed on
any failure, so no half-written file ever has the real name. Standard library only."""
import contextlib
import os
import tempfile


@contextlib.contextmanager
def atomic_path(path):
    """with atomic_path(out) as tmp: write tmp (it exists, empty) -> renamed over out."""
    path = os.fspath(path)
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(path)),
                               prefix=os.path.basename(path) + ".tmp-")
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp's 0600: an output gets what any new file would
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.remove(tmp)
        raise


def write_text_atomically(path, text):
    with atomic_path(path) as tmp:
        with open(tmp, "w") as f:
            f.write(text)
