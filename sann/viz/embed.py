"""Offline meshcat scenes: record drawing commands in-process and embed them as static HTML.

A `meshcat.Visualizer` normally talks to a zmq server process that keeps the scene tree and
serves a web viewer. For a book that must build offline and be read from disk we need neither:
`SceneRecorder` takes the server's place inside the Python process, keeps the same scene tree
(so later commands on a path replace earlier ones exactly as in the server) and writes the same
self-contained HTML the server's ``get_scene`` would. `Scene` wraps a recorder and decides how
to show itself:

- ``static`` (the built book, tests, plain Python): an ``<iframe srcdoc=...>`` holding the viewer
  page and the drawing commands; no server, no network.
- ``live`` (JupyterLab, `make lab`): the recorded commands are replayed into a real meshcat
  server and the cell shows its live viewer.

meshcat's viewer script (three.js and meshcat, ~850 kB) is either inlined into every scene or,
when the environment variable ``SANN_MESHCAT_JS`` names a URL (the book's ``conf.py`` sets it
to the copy under ``_static``), loaded from that one shared file — a chapter with five scenes
then weighs kilobytes, not megabytes.
"""

from __future__ import annotations

import base64
import html
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import meshcat
import umsgpack

#: Environment variable: URL of a shared copy of meshcat's viewer script (empty: inline it).
JS_URL_ENV = "SANN_MESHCAT_JS"
#: Environment variable forcing how scenes display: ``static`` or ``live``.
MODE_ENV = "SANN_VIEWER"
MODES = ("auto", "static", "live")


def viewer_js_path() -> Path:
    """The minified meshcat viewer script shipped inside the meshcat package."""
    return Path(meshcat.viewer_assets_path()) / "dist" / "main.min.js"


@dataclass
class _Node:
    """One path of the scene tree, holding the last packed command of each kind."""

    object: bytes | None = None
    transform: bytes | None = None
    properties: list[bytes] = field(default_factory=list)
    animation: bytes | None = None
    children: dict[str, _Node] = field(default_factory=dict)

    def walk(self) -> Iterator[_Node]:
        yield self
        for child in self.children.values():
            yield from child.walk()


class SceneRecorder:
    """In-process stand-in for meshcat's `ViewerWindow` that records instead of sending.

    Mirrors the bookkeeping of ``meshcat.servers.zmqserver`` (set_object resets the node's
    properties, delete drops a subtree, the root path clears everything), so the static page
    shows what a live viewer would show after the same calls.
    """

    def __init__(self) -> None:
        self.root = _Node()
        self.web_url = ""

    def _node(self, path: list[str]) -> _Node:
        node = self.root
        for name in path:
            node = node.children.setdefault(name, _Node())
        return node

    def send(self, command: object) -> None:
        """Record one meshcat command (the object `Visualizer` hands its window)."""
        data = command.lower()  # type: ignore[attr-defined]
        kind = data["type"]
        path = [p for p in data["path"].split("/") if p]
        packed = umsgpack.packb(data)
        if kind == "delete":
            self._delete(path)
        elif kind == "set_object":
            node = self._node(path)
            node.object, node.properties = packed, []
        elif kind == "set_transform":
            self._node(path).transform = packed
        elif kind == "set_property":
            self._node(path).properties.append(packed)
        elif kind == "set_animation":
            self._node(path).animation = packed
        else:
            raise ValueError(f"meshcat command {kind!r} cannot be recorded for a static scene")

    def _delete(self, path: list[str]) -> None:
        if not path:
            self.root = _Node()
            return
        parent = self.root
        for name in path[:-1]:
            parent = parent.children.get(name)
            if parent is None:
                return
        parent.children.pop(path[-1], None)

    def commands(self) -> list[bytes]:
        """Packed commands in replay order: per node object, properties, transform, animation."""
        out: list[bytes] = []
        for node in self.root.walk():
            if node.object is not None:
                out.append(node.object)
            out.extend(node.properties)
            if node.transform is not None:
                out.append(node.transform)
            if node.animation is not None:
                out.append(node.animation)
        return out

    def get_scene(self, js_url: str | None = None) -> str:
        """The standalone viewer page (what `Visualizer.static_html()` returns)."""
        return scene_page(self.commands(), js_url=js_url)

    def close(self) -> None:
        """Nothing to close: kept for `Visualizer.close()`."""


def scene_page(commands: list[bytes], js_url: str | None = None) -> str:
    """An HTML page that builds a meshcat viewer and replays packed commands into it.

    With ``js_url`` the viewer script is loaded from that URL; without it the script is
    inlined, so the page works on its own, offline.
    """
    if js_url:
        script = f'<script src="{html.escape(js_url, quote=True)}"></script>'
    else:
        script = "<script>" + viewer_js_path().read_text(encoding="utf-8") + "</script>"
    payload = ",".join(f'"{base64.b64encode(c).decode("ascii")}"' for c in commands)
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>SANN scene</title>
<style>body{{margin:0}}#meshcat-pane{{width:100vw;height:100vh;overflow:hidden}}
#sann-error{{font:14px sans-serif;padding:1em}}</style></head>
<body><div id="meshcat-pane"></div>
{script}
<script>
(function () {{
  var pane = document.getElementById("meshcat-pane");
  if (typeof MeshCat === "undefined") {{
    pane.innerHTML = '<p id="sann-error">The meshcat viewer script could not be loaded.</p>';
    return;
  }}
  var viewer = new MeshCat.Viewer(pane);
  var commands = [{payload}];
  for (var i = 0; i < commands.length; i++) {{
    var raw = atob(commands[i]);
    var bytes = new Uint8Array(raw.length);
    for (var j = 0; j < raw.length; j++) bytes[j] = raw.charCodeAt(j);
    viewer.handle_command_bytearray(bytes);
  }}
  window.sannViewer = viewer;
}})();
</script></body></html>"""


def iframe(page: str, height: int = 420, title: str = "3D scene") -> str:
    """Wrap a page into an ``<iframe srcdoc>`` that can sit in a notebook output."""
    if height <= 0:
        raise ValueError(f"height must be positive, got {height}")
    srcdoc = html.escape(page, quote=True)
    return (
        f'<div class="sann-scene" style="height:{height}px;width:100%;resize:vertical;'
        f'overflow:hidden"><iframe class="sann-scene-frame" title="{html.escape(title)}" '
        f'srcdoc="{srcdoc}" style="width:100%;height:100%;border:none"></iframe></div>'
    )


def in_jupyter_server() -> bool:
    """True inside a kernel that a Jupyter server (JupyterLab) started.

    jupyter_server puts ``JPY_SESSION_NAME`` into its kernels' environment; nbclient (the book
    build and the chapter tests) does not, so only an interactive session goes live.
    """
    return bool(os.environ.get("JPY_SESSION_NAME"))


def resolve_mode(mode: str = "auto") -> str:
    """``static`` or ``live``: the argument, else ``$SANN_VIEWER``, else the environment."""
    if mode not in MODES:
        raise ValueError(f"viewer mode must be one of {MODES}, got {mode!r}")
    if mode == "auto":
        mode = os.environ.get(MODE_ENV, "auto") or "auto"
        if mode not in MODES:
            raise ValueError(f"${MODE_ENV} must be one of {MODES}, got {mode!r}")
    if mode == "auto":
        mode = "live" if in_jupyter_server() else "static"
    return mode


class Scene:
    """A recorded meshcat scene that displays itself statically or in a live viewer.

    ``scene.vis`` is an ordinary `meshcat.Visualizer` (``scene.vis["blocks/A"].set_object(...)``)
    whose commands are recorded; the scene builders in `sann.viz.meshcat_scenes` return these.
    """

    def __init__(self, title: str = "3D scene", height: int = 420, mode: str = "auto") -> None:
        resolve_mode(mode)  # reject a bad mode now, not at display time
        self.recorder = SceneRecorder()
        self.vis = meshcat.Visualizer(window=self.recorder)
        self.title = title
        self.height = height
        self.mode = mode
        self._live: meshcat.Visualizer | None = None

    def static_html(self, js_url: str | None = None) -> str:
        """The scene as a page; the viewer script inlined unless a URL is given."""
        return self.recorder.get_scene(js_url=js_url)

    def iframe_html(self) -> str:
        """The ``<iframe srcdoc>`` the book embeds (shared script when the book provides one)."""
        page = self.static_html(js_url=os.environ.get(JS_URL_ENV) or None)
        return iframe(page, height=self.height, title=self.title)

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write a self-contained page (viewer script inlined) that opens offline."""
        out = Path(path)
        out.write_text(self.static_html(), encoding="utf-8")
        return out

    def live(self, vis: meshcat.Visualizer | None = None) -> meshcat.Visualizer:
        """Replay the scene into a live meshcat viewer (a new server unless one is given)."""
        target = vis if vis is not None else meshcat.Visualizer()
        target.delete()
        for packed in self.recorder.commands():
            _replay(target, packed)
        self._live = target
        return target

    def _repr_html_(self) -> str:
        if resolve_mode(self.mode) == "live":
            try:
                vis = self._live or self.live()
                return vis.jupyter_cell(height=self.height).data
            except OSError as err:  # no server could start: fall back to the static view
                print(f"meshcat live viewer unavailable ({err}); showing a static scene")
        return self.iframe_html()

    def __repr__(self) -> str:
        return f"<Scene {self.title!r}: {len(self.recorder.commands())} commands>"


def _replay(vis: meshcat.Visualizer, packed: bytes) -> None:
    """Send one recorded command, already packed, through a live visualizer's window."""
    data = umsgpack.unpackb(packed)
    window = vis.window
    window.zmq_socket.send_multipart(
        [data["type"].encode("utf-8"), data.get("path", "").encode("utf-8"), packed]
    )
    window.zmq_socket.recv()
