"""``rig-gcs stability``: the FLC stability analysis (Eq. 16-32) from the command line.

Prints the report section (Markdown) or, with ``--json``, :meth:`StabilityResult.to_dict`.
Exit codes: 0 the LMI derived from Eq. 19-25 is feasible for the configured gains; 1 it is
not (the explanation is still printed), or the analysis could not run (cvxpy missing: the
message says how to install it); 2 bad arguments or parameters.

``--set`` takes rig parameters (``flc.d1_phi_deg=2``) and analysis settings with the
``stability.`` prefix (``stability.fit.scale=0.5``, see gcs_tools/stability/settings.toml).
"""

from __future__ import annotations

import json

from gcs_tools.errors import EXIT_FAILED, EXIT_OK, UsageError


def add_arguments(p) -> None:
    p.add_argument("--airframe", default="hilms", help="airframe preset (Table 2): %(default)s")
    p.add_argument("--config", action="append", default=[], metavar="FILE", help="rig TOML parameter file (repeatable)")
    p.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE",
        help="override a rig parameter (flc.d1_phi_deg=2) or an analysis setting (stability.fit.scale=0.5); repeatable",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of the Markdown section")


def run(args) -> int:
    from rig_emulator.config.loader import ConfigError, load_config, parse_override

    from gcs_tools.stability import analyse, load_settings
    from gcs_tools.stability.settings import PREFIX

    rig, analysis = {}, {}
    try:
        for text in args.set:
            key, value = parse_override(text)
            (analysis if key.startswith(PREFIX) else rig)[key] = value
        cfg = load_config(airframe=args.airframe, files=args.config, overrides=rig)
        settings = load_settings(analysis)
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    result = analyse(cfg, settings)
    if args.json:
        print(json.dumps(result.to_dict(), indent=2, allow_nan=False))
    else:
        print(result.to_markdown())
    return EXIT_OK if result.feasible else EXIT_FAILED
