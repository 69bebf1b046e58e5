"""The one exception a user sees for bad input."""


class CaseError(ValueError):
    """Bad input in a case (file, override or API call): a one-line message naming the bad value.

    The command line prints the message alone (no traceback) and exits with status 2.
    """
