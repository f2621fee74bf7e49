"""The one error type for a user's mistake: the CLI prints it on one line and exits 2."""


class UserError(Exception):
    """A mistake in the user's input (scene file, flag, path): printed as one line, exit 2."""


class SceneError(UserError):
    """A scene file that does not follow docs/scene-format.md. The message names file and key."""

    def __init__(self, path, key: str, expected: str):
        self.path, self.key, self.expected = str(path), key, expected
        where = f"{self.path}: {key}: " if key else f"{self.path}: "
        super().__init__(where + expected)
