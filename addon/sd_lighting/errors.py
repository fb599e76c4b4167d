"""The error a bake, its storage and its removal raise for the user."""


class BakeError(Exception):
    """A bake that cannot run or failed, with a message for the user (the operators report it)."""
