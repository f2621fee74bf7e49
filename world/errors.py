"""The one error type for a user's mistake: the CLI prints it on one line and exits 2.

Its text goes through `printable`, so a name or path holding a newline or a terminal
escape sequence can neither split the line nor reach the terminal."""


def printable(text) -> str:
    """`text` as one printable line: every character str.isprintable refuses (newlines,
    tabs, escape, other controls, line and paragraph separators, unassigned code points)
    written as Python writes it in a repr: \\n, \\t, \\x1b, \\u2028, ...; backslashes
    left as they are."""
    s = str(text)
    if s.isprintable():
        return s
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in s)


class UserError(Exception):
    """A mistake in the user's input (scene file, flag, path): printed as one line, exit 2."""

    def __str__(self) -> str:
        return printable(super().__str__())


class SceneError(UserError):
    """A scene file that does not follow docs/scene-format.md. The message names file and key."""

    def __init__(self, path, key: str, expected: str):
        self.path, self.key, self.expected = str(path), key, expected
        where = f"{self.path}: {key}: " if key else f"{self.path}: "
        super().__init__(where + expected)
