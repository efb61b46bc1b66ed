"""``hapticrom explore``: the design explorer in the browser, served locally.

    hapticrom explore [MODEL] [--port 8024] [--open]
    hapticrom explore nn-default --build-only --out site/

The explorer (``embed/explorer``) is a static page that runs the model itself with
onnxruntime-web: this command builds it when needed (``node embed/explorer/build.mjs``; the
first time it runs ``npm ci`` in ``embed/``) and serves the built directory on
``http://127.0.0.1:PORT/`` until interrupted. MODEL is a model directory or a name
(:func:`surrogate.runtime.models.find_model`); the page refuses a model whose card is not
sealed (``card_sha256``, docs/embedding.md), so this command refuses it first.
"""

from __future__ import annotations

import argparse
import functools
import json
import shutil
import subprocess
import webbrowser
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, ClassVar

__all__ = ["EMBED", "build_explorer", "make_server", "register"]

EMBED = Path(__file__).resolve().parents[2] / "embed"
SOURCES = ("lib/hapticrom-model.mjs", "explorer/app.mjs", "explorer/array.mjs",
           "explorer/build.mjs", "explorer/index.html", "explorer/style.css",
           "package-lock.json")


def _sealed_model(model: str) -> tuple[Path, dict[str, Any]]:
    """The model's directory and card, its files verified and its card sealed."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.runtime.card import ModelFileError, read_card
    from surrogate.runtime.models import find_model, is_steady_state

    path = find_model(model).resolve()
    card = read_card(path)
    if not isinstance(card.get("card_sha256"), str):
        raise ModelFileError("card_sha256", f"{path}: the card is not sealed (no card_sha256); "
                             "the explorer refuses unsealed cards (docs/embedding.md)")
    if not is_steady_state(card):
        raise ModelFileError("kind", f"{path}: a {card.get('kind')!r} model; the explorer "
                             "shows steady-state predictors (a card with an ONNX graph)")
    return path, card


def _up_to_date(out: Path, model: Path, card: dict[str, Any]) -> bool:
    stamp = out / "build.json"
    if not stamp.is_file():
        return False
    built = json.loads(stamp.read_text())
    if built.get("model") != str(model) or built.get("card_sha256") != card["card_sha256"]:
        return False
    newest = max((EMBED / s).stat().st_mtime for s in SOURCES)
    return newest <= stamp.stat().st_mtime


def build_explorer(model: str, out: Path | None = None, *, force: bool = False) -> Path:
    """Build the explorer for ``model`` into ``out`` (default embed/explorer/dist) unless it
    is up to date; returns the directory to serve. Raises ``OSError`` when node or the
    embed/ sources are missing, ``ModelFileError`` for a model that fails its checks."""
    path, card = _sealed_model(model)
    out = (out or EMBED / "explorer" / "dist").resolve()
    if not force and _up_to_date(out, path, card):
        return out
    if not (EMBED / "explorer" / "build.mjs").is_file():
        raise FileNotFoundError(f"{EMBED}: the explorer sources are not here (the command "
                                "builds from a source checkout of hapticrom)")
    node, npm = shutil.which("node"), shutil.which("npm")
    if node is None or npm is None:
        raise FileNotFoundError("node and npm are needed to build the explorer "
                                "(install Node.js >= 18)")
    if not (EMBED / "node_modules" / "esbuild").is_dir():
        print("installing the explorer's npm packages (npm ci in embed/) ...")
        subprocess.run([npm, "ci", "--no-audit", "--no-fund"], cwd=EMBED, check=True)
    tmp = out.with_name(out.name + ".building")  # nothing half-built where the page is served
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        subprocess.run([node, "explorer/build.mjs", "--model", str(path), "--out", str(tmp)],
                       cwd=EMBED, check=True)
        shutil.rmtree(out, ignore_errors=True)
        tmp.rename(out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return out


class _Handler(SimpleHTTPRequestHandler):
    extensions_map: ClassVar[dict[str, str]] = {**SimpleHTTPRequestHandler.extensions_map,
                                                ".mjs": "text/javascript",
                                                ".wasm": "application/wasm"}

    def log_request(self, code: int | str = "-", size: int | str = "-") -> None:
        """Quiet: errors are still logged (log_error), successful requests are not."""


def make_server(directory: Path, host: str = "127.0.0.1", port: int = 8024) -> ThreadingHTTPServer:
    """A static file server of ``directory`` (port 0: any free port)."""
    handler = functools.partial(_Handler, directory=str(directory))
    return ThreadingHTTPServer((host, port), handler)


def _run(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.runtime.defaults import default_model

    model = default_model("harmonic") if args.model is None else args.model
    out = build_explorer(model, Path(args.out) if args.out else None, force=args.rebuild)
    if args.build_only:
        print(f"explorer built in {out}")
        return 0
    server = make_server(out, args.host, args.port)
    url = f"http://{args.host}:{server.server_address[1]}/"
    print(f"serving the design explorer at {url} (Ctrl-C to stop)", flush=True)
    if args.open:
        webbrowser.open(url)
    try:
        server.serve_forever()
    finally:
        server.server_close()
    return 0


def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"{value} is not in 0..65535")
    return value


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``explore`` subcommand."""
    p = subparsers.add_parser("explore", help="the design explorer in the browser (served "
                              "locally; the page runs the model itself)")
    p.add_argument("model", nargs="?", default=None,
                   help="model directory or name (default: the default harmonic model, "
                   "nn-sweep when installed, else nn-default)")
    p.add_argument("--port", type=_port, default=8024, help="port (default 8024; 0: any free)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--out", metavar="DIR", help="build directory (default embed/explorer/dist)")
    p.add_argument("--rebuild", action="store_true", help="build even when up to date")
    p.add_argument("--build-only", action="store_true", help="build, do not serve")
    p.add_argument("--open", action="store_true", help="open the page in the default browser")
    p.set_defaults(func=_run)
