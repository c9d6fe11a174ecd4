"""`pathtrace view`: the interactive viewer (app/viewer/)."""

from pathtrace.cli.options import SCENES_EPILOG, _int_range, add_render_options, apply_render_options
from pathtrace.errors import UserError

def cmd_view(args):
    from pathtrace import api
    from pathtrace.scene import find_scene

    if args.device and len(args.device) > 1:
        raise UserError("--device: the viewer renders on one device; give one (several are "
                        "for 'pathtrace render')")
    from pathtrace.viewer.needs_display import require_display
    try:
        require_display(args.scene)      # before any device work
    except UserError:
        find_scene(args.scene)           # a name that names no scene is the first thing to say
        raise
    api.view(lambda: apply_render_options(api.load(args.scene), args), (args.device or ["auto"])[0], size=args.size,
             frames=args.frames, screenshot_dir=args.screenshot_dir, screenshot=args.screenshot)
    return 0


def add_parser(sub):
    """The `view` command's parser."""
    p = sub.add_parser("view", help="open the interactive viewer", epilog=SCENES_EPILOG)
    p.add_argument("scene", nargs="?", default="simple",
                   help="a .toml, Mitsuba 3 .xml or pbrt-v4 .pbrt file, or a built-in name (default simple)")
    p.add_argument("--screenshot-dir", default="screenshots", metavar="DIR",
                   help="where P / F12 / the panel's button write PNG + EXR (default ./screenshots)")
    p.add_argument("--frames", type=_int_range(1), metavar="N", help="close after N frames (for scripts)")
    p.add_argument("--screenshot", action="store_true", help="take a screenshot when closing")
    add_render_options(p, queue_auto=False)     # no trial renders in the viewer: its panel sets N
    p.set_defaults(func=cmd_view)
