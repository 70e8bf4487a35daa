"""Error types of mechgen.

Every error a user can cause with a file or a flag is an :class:`InputError`; the
CLI turns it into one paragraph on stderr and exit code 2. Other errors are
numerical (:class:`ConvergenceError`, :class:`KernelError`) or environmental
(:class:`CompilerUnavailable`).
"""
from __future__ import annotations


def did_you_mean(name: object, names) -> str:
    """`` (did you mean 'x'?)`` for the known name closest to a mistyped ``name`` (difflib's ratio >= 0.6), or ''."""
    import difflib

    if not isinstance(name, str):
        return ""
    close = difflib.get_close_matches(name, [str(n) for n in names], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def file_kind(mode: int) -> str:
    """What an ``os.stat`` mode says a path is, for messages: "a folder", "a character device", "a FIFO"..."""
    import stat

    kinds = ((stat.S_ISREG, "a regular file"), (stat.S_ISDIR, "a folder"), (stat.S_ISLNK, "a symbolic link"),
             (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
             (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"))
    return next((name for test, name in kinds if test(mode)), "not a regular file")


class MechgenError(Exception):
    """Base class of every error mechgen raises on purpose."""


class InputError(MechgenError):
    """Bad user input: names the file, the key and what was expected.

    Args:
        message: what is wrong, in one sentence.
        file: the file the input came from (scene, model module), if any.
        key: the dotted key inside that file (``analysis[1].kind``), if any.
        expected: what would have been accepted.
    """

    def __init__(self, message: str, *, file: str | None = None, key: str | None = None,
                 expected: str | None = None) -> None:
        self.message = message
        self.file = file
        self.key = key
        self.expected = expected
        super().__init__(self.paragraph())

    def __reduce__(self):
        """Pickled with its parts, so that one raised in a worker process keeps its file, key and expected."""
        return _restore, (type(self), self.message, self.file, self.key, self.expected)

    def paragraph(self) -> str:
        """The one-paragraph message the CLI prints."""
        where = []
        if self.file:
            where.append(f"in {self.file}")
        if self.key:
            where.append(f"at key '{self.key}'")
        text = self.message.rstrip(".")
        if where:
            text = f"{' '.join(where)}: {text}"
        if self.expected:
            text += f"; expected {self.expected}"
        return text + "."


def _restore(cls, message: str, file: str | None, key: str | None, expected: str | None) -> InputError:
    """An InputError (or subclass) from its pickled parts."""
    return cls(message, file=file, key=key, expected=expected)


class SceneError(InputError):
    """A scene file (or a ``--set`` override) is malformed."""


class ModelError(InputError):
    """A model declaration is invalid (bad identifier, unknown parameter, ...)."""


class CompilerUnavailable(MechgenError):
    """No working C compiler was found; callers fall back to numpy."""


class BuildError(MechgenError):
    """The C compiler rejected generated code (a bug in mechgen, not in the input)."""


class KernelError(MechgenError):
    """A kernel produced NaN or Inf; names the kernel and the offending input."""


class ConvergenceError(MechgenError):
    """An iterative solver did not converge; says how far it got."""
