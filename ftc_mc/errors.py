"""Exceptions that the command line reports as one line with exit code 2."""


class UserError(Exception):
    """A problem with the user's input (config, options, paths)."""
