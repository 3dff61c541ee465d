"""Serve the built book on 127.0.0.1 so its live Soar cells run (``make serve``).

A page opened from disk cannot start the Web Worker that runs the engine, hence a server. The
standard library's handler takes its MIME types from the system's tables, which do not always
know ``.mjs`` (module scripts must be served as JavaScript) or ``.wasm``; this one says them.

    python -m sann.serve [DIRECTORY] [--port N]
"""

from __future__ import annotations

import argparse
import functools
import http.server
import threading
from pathlib import Path

DEFAULT_DIRECTORY = Path(__file__).resolve().parents[1] / "book" / "_build" / "html"
TYPES = {".mjs": "text/javascript", ".js": "text/javascript", ".wasm": "application/wasm",
         ".json": "application/json", ".zip": "application/zip"}


class Handler(http.server.SimpleHTTPRequestHandler):
    """Static files with the live book's MIME types, and no request log on the terminal."""

    extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map, **TYPES}

    def log_message(self, format: str, *args: object) -> None:
        return


def server(directory: Path, port: int = 0) -> http.server.ThreadingHTTPServer:
    """A server of ``directory`` on 127.0.0.1 (``port`` 0: any free port)."""
    handler = functools.partial(Handler, directory=str(directory))
    return http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)


def serve_in_thread(directory: Path) -> tuple[http.server.ThreadingHTTPServer, str]:
    """Start serving in a daemon thread; the server and its base URL."""
    httpd = server(directory)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    return httpd, f"http://127.0.0.1:{httpd.server_address[1]}/"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory", nargs="?", type=Path, default=DEFAULT_DIRECTORY)
    parser.add_argument("--port", type=int, default=8000)
    args = parser.parse_args(argv)
    if not (args.directory / "index.html").is_file():
        raise SystemExit(f"{args.directory} holds no built book: run `make book` first")
    httpd = server(args.directory, args.port)
    print(f"The live book: http://127.0.0.1:{httpd.server_address[1]}/index.html "
          "(Ctrl+C stops the server)", flush=True)
    try:
        httpd.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        httpd.server_close()


if __name__ == "__main__":
    main()
