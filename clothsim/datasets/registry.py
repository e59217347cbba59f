"""The data sets clothsim knows: what each holds, where it comes from, each file's SHA-256.

``liu13-port`` ships inside the package (``liu13-port.tar.xz``, the exact text files);
``jacobson-a8`` is third-party and downloaded on first use from its public repository at a
pinned commit, every file checked against the SHA-256 below (computed from the files of
that commit).
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Dataset:
    """One data set: a folder of files, each pinned by its SHA-256.

    Attributes
    ----------
    name : str
        The folder name, also the first part of a scene's ``data:<name>/...`` paths.
    title : str
        What it is, in one line.
    files : dict of str to str
        File path inside the folder (``/``-separated) to its SHA-256 (hex).
    source : str
        Where it comes from, in one line.
    archive : str or None
        For a bundled data set: the archive inside :mod:`clothsim.datasets` holding it.
    readme : str or None
        For a bundled data set: the page written into the folder as ``README.md``.
    url : str or None
        For a downloaded data set: the base URL its files are fetched from
        (``<url>/<file>``).
    loose_folder : bool
        ``$CLOTHSIM_DATA`` may name the data set's folder itself (a checkout's ``data/``),
        not only a folder holding ``<name>/``.
    """

    name: str
    title: str
    files: dict = field(repr=False)
    source: str
    archive: str | None = None
    readme: str | None = None
    url: str | None = None
    loose_folder: bool = False

    @property
    def bundled(self) -> bool:
        """Ships inside the package (no download)."""
        return self.archive is not None


LIU13 = Dataset(
    name="liu13-port",
    title="the paper authors' own C++ code run on its default scene: model, M, L, A, J, "
          "61 frames of positions and velocities (the port checker's reference)",
    source="clothsim's own run of chunleili/fast_mass_spring at 3b1a6dd, shipped in the "
           "package (clothsim/datasets/liu13-port.md)",
    archive="liu13-port.tar.xz",
    readme="liu13-port.md",
    files={
        "default-scene/A.mtx":
            "4de2f24d0f64e3183e1cf1bfd6ef02ad02a1cc8e10ad7594b31f065f7f3fbf23",
        "default-scene/J.mtx":
            "cecccd4bbf5e71e3522826d9567d9416a434376933a937bbd709efe3b97de0c7",
        "default-scene/L.mtx":
            "b09c61a55510f483f8eafcd68e7bb6623e62b22fcc7c8b89c4659cc81b116aa1",
        "default-scene/M.mtx":
            "450b390580297066c2c4f0842540662c6ab7b84afbd23f5682aaf992e24d0e94",
        "default-scene/positions.txt":
            "7914346bf675a10cced74b1286120419798e748f292b477fd792641ea3ec0d96",
        "default-scene/springs.txt":
            "6c73add7bb1258bf6f0a4f61e392e76ca5796528c2b652b997af70857b194239",
        "default-scene/triangles.txt":
            "5250f27809ef05272e6c2b99c9d8061af25e6d962a9f4ebb1eca85a48e719179",
        "default-scene/velocities.txt":
            "a98269a95c52368062e324a0e25faaf9610a80da3465996fa8e4d729bfcafafc",
        "default-scene/x0.txt":
            "af6cbabbb434a1bdbd2dd57a597394670cfd71605911b8241feead3ebcc453cc",
    },
)

#: The commit of alecjacobson/computer-graphics-mass-spring-systems the files are pinned to.
JACOBSON_COMMIT = "7926d85482f430669bf955340e3facc0790d8096"

JACOBSON = Dataset(
    name="jacobson-a8",
    title="A. Jacobson's mass-spring assignment scenes (spring, chain, net, flag, skirt): "
          "the built-in jacobson-* scenes read them",
    source=f"github.com/alecjacobson/computer-graphics-mass-spring-systems, folder data/, "
           f"commit {JACOBSON_COMMIT[:7]} (third party, not redistributed)",
    url=("https://raw.githubusercontent.com/alecjacobson/computer-graphics-mass-spring-systems/"
         f"{JACOBSON_COMMIT}/data/"),
    loose_folder=True,
    files={
        "flag.json": "a80090228cb43c6a06ebf2adb50edeb0b3491e4a87b586eafc524f426892d0b5",
        "flag.obj": "3f35c75a35f69f350c32dd5c7d3588f2ecd97f0b6ec4c15b0405a7aef1feb239",
        "horizontal-chain.json":
            "edc0cc86d195a3e24f923835d74954fb42c54dea8e3f5abd9b9129f886f377fe",
        "horizontal-chain.obj":
            "38e33309fce41a49e956e89cd09aa8d7af0448aae7595634c8b561da9fbacd20",
        "net.json": "2f336b2e669f997fd1f7057c5909ff53d761440f5c39ab02767599e533c081b9",
        "net.obj": "7a462d420544b925f48996051dedb5c49683c36ec348214879e3bc573bf7f8b6",
        "single-spring-horizontal.json":
            "26d95304fca04faa690fbee02f25ed8f7c33494a9f6873c8d69b6bac8f8b1369",
        "single-spring-horizontal.obj":
            "80b63cc74faede06e58ad2f0ecf2dc0c41579fc2795803ac97ecce7e99bf9a83",
        "skirt.json": "ab69984e8c54efdd13067c76c8828b9a6ec66916073696d7a57f860fd998ca1b",
        "skirt.obj": "12c3748b90713fe992d1bc13f12f66d4c9d0f5faf2c5542ecd2e6ad931fa897d",
    },
)

#: Every data set, by name.
DATASETS = {d.name: d for d in (LIU13, JACOBSON)}

__all__ = ["Dataset", "DATASETS", "LIU13", "JACOBSON", "JACOBSON_COMMIT"]
