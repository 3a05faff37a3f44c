"""How a subcommand is declared in a command table (`sim.cli.COMMANDS`): a class that imports
nothing, so that the table is read as fast as Python starts."""

from __future__ import annotations


class Command:
    """One subcommand of a command table.

    Attributes:
        name: what is typed (``reform-sim NAME``).
        help: its line in the table's help.
        arguments: the module adding its arguments: ``DESCRIPTION`` (shown as written) and
            ``add_arguments(parser)``, which sets the ``handler`` default (`run_with`).
        aliases: other names for it.
    """

    __slots__ = ("name", "help", "arguments", "aliases")

    def __init__(self, name: str, help: str, arguments: str, aliases: tuple[str, ...] = ()):
        self.name = name
        self.help = help
        self.arguments = arguments
        self.aliases = tuple(aliases)

    def __repr__(self) -> str:
        return (
            f"Command(name={self.name!r}, help={self.help!r}, arguments={self.arguments!r}, "
            f"aliases={self.aliases!r})"
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Command):
            return NotImplemented
        return (self.name, self.help, self.arguments, self.aliases) == (
            other.name,
            other.help,
            other.arguments,
            other.aliases,
        )

    def __hash__(self) -> int:
        return hash((self.name, self.help, self.arguments, self.aliases))
