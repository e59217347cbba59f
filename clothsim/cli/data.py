"""``clothsim data``: list, fetch and locate the data sets (:mod:`clothsim.datasets`).

::

    clothsim data list [--verify]
    clothsim data fetch [NAME ...] [--into DIR] [--url URL]
    clothsim data path NAME[/FILE]

Any other command takes ``data:<name>/<path>`` where it takes a file or folder
(:func:`expand_data_args`).
"""

from __future__ import annotations

from .common import _fail, _Parser


def _add_data_command(sub) -> None:
    """The ``data`` command and its actions."""
    from ..datasets import DATASETS

    names = ", ".join(DATASETS)
    data = sub.add_parser("data", help="list, fetch and locate the data sets: the shipped port "
                          "reference (liu13-port), the assignment's scenes (jacobson-a8, "
                          "downloaded on first use)")
    actions = data.add_subparsers(dest="data_action", metavar="ACTION", parser_class=_Parser,
                                  help="list, fetch or path")
    actions.required = True
    lst = actions.add_parser("list", help="each data set: what it is, where, whether it is there")
    lst.add_argument("--verify", action="store_true",
                     help="also check every file against its pinned SHA-256")
    fet = actions.add_parser("fetch", help="get data sets now (download or unpack), checking "
                             "every file's SHA-256; files already there are kept")
    fet.add_argument("names", nargs="*", metavar="NAME", help=f"data sets ({names}; default all)")
    fet.add_argument("--into", metavar="DIR", default=None,
                     help="put them in DIR/<name>/ (then CLOTHSIM_DATA=DIR finds them) instead "
                     "of the cache folder")
    fet.add_argument("--url", metavar="URL", default=None,
                     help="download from this mirror (URL/<file>) instead of the data set's "
                     "own address; files are still checked against their SHA-256")
    pth = actions.add_parser("path", help="print the folder of a data set (or of a file in it), "
                             "getting it first if needed")
    pth.add_argument("target", metavar="NAME[/FILE]", help=f"a data set ({names}), optionally "
                     "followed by a path inside it, e.g. liu13-port/default-scene")


def _state(st, how: str) -> str:
    if st.origin == "package":
        return "in the package (unpacked on first use)"
    if not st.present:
        return f"missing {st.missing} of its files: {how}"
    return "ready" + (" (CLOTHSIM_DATA)" if st.origin == "CLOTHSIM_DATA" else "")


def _list(args) -> int:
    from .. import datasets

    rows = []
    for name, ds in datasets.DATASETS.items():
        st = datasets.status(name)
        how = f"clothsim data fetch {name}"
        state = _state(st, how)
        if args.verify and st.present and st.origin != "package":
            changed = datasets.changed_files(name, st.folder)
            if changed:
                state += (f"; {len(changed)} file(s) differ from the pinned SHA-256: "
                          f"{', '.join(changed[:3])}")
            else:
                state += f"; all {len(ds.files)} files match their SHA-256"
        rows.append((name, state, st.folder, ds))
    width = max(len(r[0]) for r in rows)
    for name, state, folder, ds in rows:
        print(f"{name:<{width}}  {state}")
        print(f"{'':<{width}}  folder: {folder}")
        print(f"{'':<{width}}  {ds.title}; source: {ds.source}")
    return 0


def _fetch(args) -> int:
    from .. import datasets

    names = args.names or list(datasets.DATASETS)
    for name in names:
        datasets.dataset(name)  # every name checked before anything is fetched
    for name in names:
        ds = datasets.DATASETS[name]
        url = args.url if not ds.bundled else None
        folder = datasets.fetch(name, into=args.into, base_url=url)
        print(f"{name}: {len(ds.files)} files in {folder}")
    return 0


def _path(args) -> int:
    from .. import datasets

    name, _, inner = args.target.strip("/").partition("/")
    folder = datasets.locate(name)
    target = folder / inner if inner else folder
    try:
        inside = target.resolve().is_relative_to(folder.resolve())
    except (OSError, RuntimeError):
        inside = False
    if not inside or not target.exists():
        return _fail(f"{args.target}: no such file or folder in data set {name} ({folder})", 2)
    print(target)
    return 0


def expand_data_args(args) -> None:
    """Every argument written ``data:<name>/...`` becomes the file or folder it names
    (``clothsim check SCENE data:liu13-port/default-scene``), got first when missing.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line; its string values are replaced in place.

    Raises
    ------
    InputError
        One line: the data set cannot be got (and how to get it), or nothing is there.
    """
    from ..scene.files import DATA_PREFIX, resolve_data_path

    for key, value in vars(args).items():
        if isinstance(value, str) and value.startswith(DATA_PREFIX):
            setattr(args, key, str(resolve_data_path(value, key.upper())))


def _cmd_data(args) -> int:
    from ..datasets import DataUnavailableError

    action = {"list": _list, "fetch": _fetch, "path": _path}[args.data_action]
    try:
        return action(args)
    except DataUnavailableError as exc:
        return _fail(str(exc), 1)
