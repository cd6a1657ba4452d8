"""Errors about input a user can fix (a bad file, a bad URL). The CLI prints them as one line
naming the file and exits with code 2, without a traceback."""


class InputError(Exception):
    """Bad input that names itself: a file, a line, a URL."""
