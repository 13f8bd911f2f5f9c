"""Renamed keyword arguments that keep working, with a DeprecationWarning."""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from typing import ParamSpec, TypeVar

__all__ = ["P", "R", "renamed_keyword"]

P = ParamSpec("P")
R = TypeVar("R")


def renamed_keyword(old: str, new: str) -> Callable[[Callable[P, R]], Callable[P, R]]:
    """Let callers still pass ``old=`` for the argument now called ``new``
    (the function's first parameter).

    The wrapped function keeps its signature (type checkers and ``help`` show
    only ``new``); a call with ``old=`` warns with a DeprecationWarning and is
    passed on as ``new=``; a call with both is a TypeError.
    """

    def decorate(function: Callable[P, R]) -> Callable[P, R]:
        @functools.wraps(function)
        def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
            if old in kwargs:
                name = function.__name__
                if new in kwargs or args:
                    raise TypeError(f"{name}() got {old}= (the old name of {new}) and {new}")
                warnings.warn(
                    f"{name}({old}=...) is deprecated: the argument is called {new} now",
                    DeprecationWarning,
                    stacklevel=2,
                )
                kwargs[new] = kwargs.pop(old)
            return function(*args, **kwargs)

        return wrapper

    return decorate
