"""Usage errors (unknown option, missing argument, bad value, unknown command) as the
command line's one error line: ``fuzzygait: error: <command>: <what is wrong>; see
'<command> --help'`` (exit 1, as for any other bad input)."""

from __future__ import annotations

from typer._click.exceptions import BadParameter, MissingParameter, NoSuchOption, UsageError


def printable(text: str) -> str:
    """``text`` on one line, control characters (terminal escape codes) shown escaped."""
    text = " ".join(str(text).split())
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def _hint(exc: BadParameter) -> str:
    """The option's names (``--out / -o``) or the argument's metavar (``DYNAMIC.c3d``)."""
    if exc.param is None:
        return "a value"
    hint = exc.param.get_error_hint().replace("'", "")
    return hint.upper() if exc.param.param_type_name == "argument" and hint == exc.param.name else hint


def _given(exc: BadParameter) -> str:
    """`` 'x'`` when the value given is known (typer's validation error holds it)."""
    errors = getattr(exc.__cause__, "errors", None)
    try:
        value = errors()[0]["input"] if callable(errors) else None
    except (IndexError, KeyError, TypeError):
        value = None
    return f" {str(value)!r}" if isinstance(value, str | int | float) else ""


def _what(exc: UsageError) -> str:
    """What is wrong, lower-case, without a final full stop."""
    if isinstance(exc, NoSuchOption):
        what = f"no such option {exc.option_name}"
        if exc.possibilities:
            what += f" (did you mean {' or '.join(sorted(exc.possibilities))}?)"
        return what
    if isinstance(exc, MissingParameter):
        kind = "argument" if exc.param is not None and exc.param.param_type_name == "argument" else "option"
        return f"missing {kind} {_hint(exc)}"
    if isinstance(exc, BadParameter):
        why = exc.message.rstrip(".")
        return f"invalid value{_given(exc)} for {_hint(exc)}: {why[:1].lower() + why[1:]}"
    message = exc.format_message().strip()
    head, sep, suggestion = message.partition(". Did you mean ")
    if sep:  # "No such command 'x'. Did you mean 'y'?"
        message = f"{head} (did you mean {suggestion.rstrip('?')}?)"
    message = message.rstrip(".")
    return message[:1].lower() + message[1:]


def usage_line(exc: UsageError, command: str | None = None) -> str:
    """The one error line of a usage error: the command, what is wrong with which option
    or argument, and the command's ``--help`` to see what it takes. ``command``: the
    command's name when the error does not know it (an option's missing value)."""
    path = exc.ctx.command_path if exc.ctx is not None else "fuzzygait"
    if path == "fuzzygait" and command:
        path = f"fuzzygait {command}"
    command = path.partition(" ")[2]
    where = f"{command}: " if command else ""
    return printable(f"fuzzygait: error: {where}{_what(exc)}; see '{path} --help'")
