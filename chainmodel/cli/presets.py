"""``chainmodel presets``: the named drives (seed 000 Table 1, seed 004 Table 1, seed 003)."""

from __future__ import annotations

from ..cli_support import drive_dict, print_json

__all__ = ["register_presets", "cmd_presets"]


def register_presets(subparsers) -> None:
    p = subparsers.add_parser("presets", help="list the named drives",
                              description="The named drives: seed 000 Table 1 (coarse, medium, "
                                          "fine), seed 004 Table 1 (A1-D3), seed 003 (xu2010).")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=cmd_presets)


def cmd_presets(args) -> int:
    from ..presets import preset, preset_names
    drives = [preset(name) for name in preset_names()]
    if args.json:
        print_json({"presets": [drive_dict(d) for d in drives]})
        return 0
    print(f"{'name':<8} {'n_c':>4} {'n_o':>4} {'N':>4} {'f':>8} {'M':>5} {'p [mm]':>8} "
          f"{'centre distance [mm]':>21}")
    for d in drives:
        print(f"{d.name:<8} {d.n_driver:>4} {d.n_driven:>4} {d.span_pitches:>4} "
              f"{d.pitch_fraction:>8.4f} {d.links if d.links is not None else '-':>5} "
              f"{d.pitch * 1e3:>8.3f} {d.centre_distance * 1e3:>21.3f}")
    return 0
