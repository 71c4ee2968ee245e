"""``rig-gcs param list|get|set|save|load``: the vehicle's parameters from the command line.

* ``list CONNECTION`` - every parameter, ``NAME VALUE`` a line in index order, then the count;
* ``get CONNECTION NAME`` - one parameter;
* ``set CONNECTION NAME VALUE`` - set it and check the vehicle's echo (exit 1 if it keeps
  another value, with its reason);
* ``save CONNECTION FILE`` - every parameter to a QGroundControl ``.params`` file (atomically);
* ``load CONNECTION FILE`` - a QGroundControl ``.params`` or MAVProxy ``NAME VALUE`` file: the
  file is checked before connecting (exit 2 with the line and field), then against the
  vehicle (unknown names, values that do not fit: exit 2, nothing set), then each changed
  value is set and verified; a failure restores what was already changed (exit 1).

Protocol details and retries: :mod:`gcs_tools.params_client`; file formats:
:mod:`gcs_tools.param_files`.
"""

from __future__ import annotations


from gcs_tools.arg_types import finite_number as _value
from gcs_tools.arg_types import positive_number as positive
from gcs_tools.errors import EXIT_OK, UsageError


def add_param_parser(sub) -> None:
    p = sub.add_parser("param", help="list, get, set, save or load the vehicle's parameters",
                       description="list: every parameter (NAME VALUE); get NAME; set NAME VALUE (checked against the "
                                   "vehicle's echo); save FILE (QGroundControl .params); load FILE (QGroundControl "
                                   ".params or MAVProxy NAME VALUE; the whole file is checked first and nothing is set "
                                   "if any line is bad; a failed set restores what was changed). Exit 0 ok, 1 failed "
                                   "(link, timeout, rejected), 2 bad usage or file.")
    p.add_argument("action", choices=("list", "get", "set", "save", "load"))
    p.add_argument("connection", help="pymavlink connection string, e.g. tcp:127.0.0.1:5760")
    p.add_argument("args", nargs="*", help="get: NAME; set: NAME VALUE; save/load: FILE")
    p.add_argument("--sysid", type=int, help="vehicle system id (default: the first vehicle heard)")
    p.add_argument("--heartbeat-timeout", type=positive, default=10.0, help="seconds to wait for the vehicle: %(default)s")
    p.add_argument("--timeout", type=positive, default=1.0, help="seconds to wait for each answer: %(default)s")
    p.add_argument("--retries", type=int, default=5, help="resends of a read, write or missing index: %(default)s")
    p.set_defaults(func=cmd_param)


def _expect(args, n: int, usage: str) -> list:
    if len(args.args) != n:
        raise UsageError(f"param {args.action} needs {usage}")
    return args.args


def cmd_param(args) -> int:
    from gcs_tools.link import open_link
    from gcs_tools.param_files import load_params, save_params, value_text
    from gcs_tools.params_client import ParamClient, load

    if args.retries < 0:
        raise UsageError("--retries must be >= 0")
    lines = name = value = path = None
    if args.action == "list":
        _expect(args, 0, "no further arguments")
    elif args.action == "get":
        (name,) = _expect(args, 1, "NAME")
    elif args.action == "set":
        name, text = _expect(args, 2, "NAME VALUE")
        try:
            value = _value(text)
        except Exception as exc:  # noqa: BLE001 - argparse's message
            raise UsageError(f"param set {name}: {exc}") from None
    else:
        (path,) = _expect(args, 1, "FILE")
        if args.action == "load":
            lines = load_params(path)  # checked before connecting
    with open_link(args) as link:
        client = ParamClient(link, args.timeout, args.retries)
        if args.action == "list":
            params = sorted(client.fetch_all().values(), key=lambda p: p.index)
            for p in params:
                print(f"{p.name:16s} {value_text(p.value, p.ptype)}")
            print(f"{len(params)} parameters")
        elif args.action == "get":
            p = client.read(name)
            print(f"{p.name} {value_text(p.value, p.ptype)}")
        elif args.action == "set":
            ptype = client.read(name).ptype
            p = client.set(name, value, ptype)
            print(f"{p.name} {value_text(p.value, p.ptype)}")
        elif args.action == "save":
            params = client.fetch_all()
            save_params(path, {p.name: (p.value, p.ptype) for p in params.values()}, link.target_system,
                        link.target_component)
            print(f"saved {len(params)} parameters to {path}")
        else:
            changed, same = load(client, lines, path,
                                 report=lambda n, old, new: print(f"{n}: {old:g} -> {new:g}", flush=True))
            print(f"loaded {path}: {changed} set, {same} already equal")
    return EXIT_OK
