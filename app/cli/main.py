"""pathtrace: an interactive, progressive path tracer with OpenCL kernels."""

import argparse
import os
import re
import sys

from pathtrace import __version__
from pathtrace.cli import bench, convert, farm, listing, render, view
from pathtrace.cli.interrupts import interrupted, interrupted_status
from pathtrace.cli.options import SCENES_EPILOG
from pathtrace.errors import UserError, cut, did_you_mean

COMMANDS = (render, view, bench, farm, convert, listing)     # each adds its parsers, in the order help lists them


def build_parser():
    parser = Parser(prog="pathtrace", description=__doc__, epilog=SCENES_EPILOG)
    parser.add_argument("--version", action="version", version=f"pathtrace {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(sub)
    return parser


class Parser(argparse.ArgumentParser):
    """argparse's parser, whose messages echo what the user typed cut short: argparse quotes an
    invalid choice or an unknown option whole, however long, and an ambiguous one raw."""

    MESSAGE_LIMIT = 400

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # a value that starts with a minus and a digit ('--size -64x48', '--exposure -.5') is the
        # option's value, which its type then refuses where it must, in one line; argparse took
        # '-64x48' for an unknown option and said "expected one argument". No option of
        # pathtrace's starts so.
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def format_help(self):
        if self.epilog == SCENES_EPILOG:
            self.epilog = listing.epilog()
        return super().format_help()

    def error(self, message):
        commands = next((a for a in self._actions if isinstance(a, argparse._SubParsersAction)), None)
        if commands and message == f"the following arguments are required: {commands.metavar}":
            message = f"give a command: {', '.join(commands.choices)}"
        # one line, as every other error's (no usage block): what was wrong, and where help is
        self.exit(2, f"{self.prog}: error: {cut(' '.join(cut(word) for word in message.split(' ')), self.MESSAGE_LIMIT)}"
                     f"{self.suggestion(message)} (see '{self.prog} -h')\n")

    def suggestion(self, message: str) -> str:
        """"; did you mean ...?" for an unknown option (among this parser's) or an invalid
        choice (among the argument's), where one is close to what was typed."""
        choice = re.match(r"argument (\S+): invalid choice: '(.*)' \(choose from (.*)\)$", message)
        if choice:
            return did_you_mean(choice[2], re.findall(r"'([^']*)'", choice[3]))
        unknown = re.match(r"unrecognized arguments: (.*)$", message)
        options = [o for a in self._actions for o in a.option_strings if o.startswith("--")]
        for word in unknown[1].split(" ") if unknown else ():
            if word.startswith("--"):
                return did_you_mean(word.split("=")[0], options)
        return ""


def parse(parser: argparse.ArgumentParser, argv):
    """parse_args, except that an unknown option is reported with the usage of the subcommand it
    was given to, not the top level's."""
    args, extra = parser.parse_known_args(argv)
    if extra:
        chosen = parser
        for dest in ("command", "farm_command"):   # down the chain of subcommands
            action = next((a for a in chosen._actions if isinstance(a, argparse._SubParsersAction)), None)
            if action is None or getattr(args, dest, None) is None:
                break
            chosen = action.choices[getattr(args, dest)]
        chosen.error(f"unrecognized arguments: {' '.join(extra)}")
    return args


def choose_program_mode(args):
    """--program, for every device this process opens and the renders it starts
    (pathtrace.device.programs). bench times the scenes' own programs' renders unless asked otherwise;
    its --load and --first-image time commands as a user runs them."""
    from pathtrace.device.programs import PROGRAM_ENV
    times_renders = args.command == "bench" and not (args.load or args.first_image)
    mode = getattr(args, "program", None) or (
        "specialised" if times_renders and not os.environ.get(PROGRAM_ENV) else None)
    if mode:
        os.environ[PROGRAM_ENV] = mode


def main(argv=None) -> int:
    """Runs one command; returns its exit status (pathtrace.cli.console: the entry point around it)."""
    args = parse(build_parser(), argv)
    try:
        choose_program_mode(args)
        if sys.stdout is None:          # started with standard output closed (>&-)
            if args.command in ("scenes", "devices", "bench"):
                raise UserError("cannot write the standard output: it is closed")
            sys.stdout = open(os.devnull, "w")
        code = args.func(args)
        sys.stdout.flush()
        return code
    except (UserError, KeyboardInterrupt) as e:
        if isinstance(e, UserError) and not interrupted():
            print(f"pathtrace: error: {e}", file=sys.stderr)
            return 1
        print("pathtrace: interrupted", file=sys.stderr)
        return interrupted_status()
    except MemoryError:
        print("pathtrace: error: out of memory (a smaller --size, fewer samples at once or a smaller "
              "scene may fit)", file=sys.stderr)
        return 1
    except OSError as e:
        if e.filename is not None or e.errno is None:
            raise                       # not standard output: a fault of ours, shown as such
        sys.stdout = open(os.devnull, "w")   # so that the exit does not try the flush again
        print(f"pathtrace: error: cannot write the standard output ({e.strerror})", file=sys.stderr)
        return 1
