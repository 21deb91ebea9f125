"""The project's output-file discipline (docs/faults.md) for the plot scripts' figures.

save_figure(fig, path, dpi=...) writes the PNG to an unnamed file (O_TMPFILE) in the target's
directory and links it in only when it is complete: as the target when there is none, else under
a temporary name renamed over the target (atomic, same directory). A failure, an interrupt or a
SIGKILL leaves the previous figure or none, never half a PNG and no temporary file. Where O_TMPFILE
or /proc is missing, a named temporary ".NAME.sdins-tmp.*" beside the target is written and
renamed instead (removed on any exception, SIGINT and SIGTERM included). A symbolic link is
followed: the file it names is replaced. Every failure raises OutputError naming the file and
the OS error, which the scripts turn into a one-line message and exit status 1.

load_json(path) reads a script's input JSON; a missing or malformed file raises InputError.
run_script(prog, main) runs main(sys.argv) as the script's body and turns an InputError, an
OutputError or any other failure into one line "PROG: error: ..." and exit status 1.

Importing this module makes SIGTERM raise SystemExit(143), so a terminated script unwinds through
the clean-up like SIGINT (KeyboardInterrupt) does.
"""
import errno
import json
import os
import signal
import sys
import tempfile


class OutputError(Exception):
    """A figure could not be written (the message names the file and the OS error)."""


class InputError(Exception):
    """An input file is missing or malformed (the message names the file)."""


def load_json(path):
    """The JSON value in path; InputError when the file is missing or not valid JSON."""
    if not os.path.isfile(path):
        raise InputError(f"{path} not found")
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        raise InputError(f"{path} is not valid JSON: {e}")


def run_script(prog, main):
    """sys.exit(main(sys.argv)), every failure kept to one line on stderr and exit status 1."""
    try:
        sys.exit(main(sys.argv))
    except (InputError, OutputError) as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        sys.exit(1)
    except Exception as e:  # keep failures to one line for `sdins paper`
        print(f"{prog}: error: {type(e).__name__}: {e}", file=sys.stderr)
        sys.exit(1)


def _on_sigterm(signum, frame):  # noqa: ARG001
    sys.exit(128 + signum)


signal.signal(signal.SIGTERM, _on_sigterm)


def _temporary_name(target):
    d, name = os.path.split(target)
    fd, tmp = tempfile.mkstemp(prefix="." + name + ".sdins-tmp.", dir=d or ".")
    os.close(fd)
    os.unlink(tmp)  # only the name is wanted (os.link and os.replace create it)
    return tmp


def _write_unnamed(fig, target, kwargs):
    """False (nothing written) when this file system or kernel has no O_TMPFILE."""
    if not hasattr(os, "O_TMPFILE") or not os.access("/proc/self/fd", os.X_OK):
        return False
    try:
        fd = os.open(os.path.dirname(target) or ".", os.O_TMPFILE | os.O_WRONLY | os.O_CLOEXEC, 0o666)
    except OSError as e:
        if e.errno in (errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL):
            return False
        raise
    with os.fdopen(fd, "wb") as f:
        fig.savefig(f, **kwargs)
        f.flush()
        os.fsync(f.fileno())
        # linkat(/proc/self/fd, "N", ..., AT_SYMLINK_FOLLOW): os.link only calls linkat (not
        # link, which would try to link the /proc entry itself) when a directory fd is given.
        proc_fd = os.open("/proc/self/fd", os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        try:
            try:
                os.link(str(f.fileno()), target, src_dir_fd=proc_fd, follow_symlinks=True)
                return True
            except FileExistsError:
                pass
            tmp = _temporary_name(target)
            os.link(str(f.fileno()), tmp, src_dir_fd=proc_fd, follow_symlinks=True)
        finally:
            os.close(proc_fd)
    try:
        os.replace(tmp, target)
    except BaseException:
        os.unlink(tmp)
        raise
    return True


def _write_named(fig, target, kwargs):
    d, name = os.path.split(target)
    fd, tmp = tempfile.mkstemp(prefix="." + name + ".sdins-tmp.", dir=d or ".")
    try:
        with os.fdopen(fd, "wb") as f:
            fig.savefig(f, **kwargs)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def save_figure(fig, path, **kwargs):
    """fig.savefig(path, **kwargs) with the discipline above; the format follows the extension."""
    target = os.path.realpath(path) if os.path.islink(path) else path
    kwargs.setdefault("format", os.path.splitext(target)[1].lstrip(".") or "png")
    try:
        if not _write_unnamed(fig, target, kwargs):
            _write_named(fig, target, kwargs)
    except OSError as e:
        raise OutputError(f"{path}: {e.strerror or e}") from e
    _note_output(path)


def _note_output(path):
    """Names a figure put in place to the sdins command that ran this script (run_plot_script sets
    SDINS_OUTPUTS_NOTE): its run directory's summary names every output of the run and removes a
    previous run's outputs that this run did not write (docs/faults.md, "run directories")."""
    note = os.environ.get("SDINS_OUTPUTS_NOTE")
    if not note:
        return
    with open(note, "a", encoding="utf-8", errors="surrogateescape") as f:
        f.write(os.path.abspath(path) + "\n")
