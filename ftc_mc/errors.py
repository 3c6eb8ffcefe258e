"""Exceptions that the command line reports as one line with exit code 2."""


class UserError(ValueError):
    """A problem with the user's input (config, options, paths, parameters).

    A :class:`ValueError`, so code that catches bad values catches it too; the
    command line turns only this one into a single line and exit code 2, and
    lets any other error show its traceback.
    """
