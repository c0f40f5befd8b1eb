"""A meshcat server that listens on one address (127.0.0.1 by default), run as a subprocess.

meshcat 0.3.2's own server binds its web server to every interface; here the tornado
application listens on ``host`` only, and the ZeroMQ command socket (which takes scene commands
without authentication) on 127.0.0.1 always, whatever ``host`` is. Started by
:func:`start_viewer`, the server exits when its parent does (it watches its stdin pipe), so a
killed parent never leaves it running.

    python -m nnrobust.outputs.viewer.server [--host 127.0.0.1] [--port 7000]
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import io
import os
import queue
import re
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass

from ...core.exceptions import NNRobustError

LOOPBACK = "127.0.0.1"


def _bridge_class():
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class LoopbackBridge(ZMQWebSocketBridge):
        """meshcat's bridge with the web server bound to ``host`` instead of all interfaces."""

        def make_app(self):
            app = super().make_app()
            listen = app.listen
            app.listen = lambda port, **kwargs: listen(port, address=self.host, **kwargs)
            return app

        def setup_zmq(self, url):
            """The command socket on 127.0.0.1, never on ``host``."""
            return super().setup_zmq(re.sub(r"//[^/]*:(\d+)$", r"//127.0.0.1:\1", url))

    return LoopbackBridge


def url_for(web_url: str, host: str) -> str:
    """The meshcat web URL with an IPv6 host in brackets (``http://[::1]:7000/``), as a browser
    needs it; other URLs unchanged.
    """
    if ":" in host and not host.startswith("["):
        return web_url.replace(f"//{host}:", f"//[{host}]:", 1)
    return web_url


def check_listen_address(host: str, port: int | None) -> None:
    """Refuse, with one clear line, an address the viewer cannot listen on."""
    if port is not None and not 1 <= port <= 65535:
        raise NNRobustError(
            f"--port {port}: a TCP port is 1 to 65535 (omit --port for the first free one from 7000)"
        )
    try:
        infos = socket.getaddrinfo(host, port or 0, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError):
        raise NNRobustError(
            f"--host {host!r} is not an address or host name this machine can resolve; "
            "use 127.0.0.1 (this machine only) or 0.0.0.0 (every interface)"
        ) from None
    family, _, _, _, address = infos[0]
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(address)
        except OSError as err:
            what = f"port {port} is in use" if err.errno == errno.EADDRINUSE else (err.strerror or str(err))
            raise NNRobustError(
                f"the viewer cannot listen on {host}:{port or 'any port'}: {what}; "
                "use an address of this machine (127.0.0.1, or 0.0.0.0 for every "
                "interface) and a free port"
            ) from None


def _exit_with_parent() -> None:
    """Exit when stdin (a pipe from the parent) closes: the parent has ended, however it ended."""

    def watch():
        sys.stdin.buffer.read()
        os._exit(0)

    threading.Thread(target=watch, daemon=True).start()


def main(argv: list[str] | None = None) -> None:
    """Serve the meshcat viewer on ``--host`` and print zmq_url=... and web_url=... lines."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default=LOOPBACK, help="address to listen on (default 127.0.0.1)")
    parser.add_argument("--port", type=int, help="web port (default: the first free from 7000)")
    parser.add_argument(
        "--exit-with-parent", action="store_true", help="exit when stdin closes (how start_viewer runs it)"
    )
    args = parser.parse_args(argv)
    if args.exit_with_parent:
        _exit_with_parent()
    bridge = _bridge_class()(host=args.host, port=args.port)
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={url_for(bridge.web_url, args.host)}", flush=True)
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass


@dataclass
class LiveViewer:
    """A running viewer: the meshcat client, the server process and the page to open."""

    vis: object
    process: subprocess.Popen
    web_url: str

    def close(self) -> None:
        """Stop the server."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()

    def __enter__(self) -> LiveViewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def start_viewer(host: str = LOOPBACK, port: int | None = None, timeout: float = 20.0) -> LiveViewer:
    """Start the server subprocess and connect a meshcat client to it."""
    import meshcat

    check_listen_address(host, port)
    cmd = [sys.executable, "-u", "-m", "nnrobust.outputs.viewer.server", "--host", host, "--exit-with-parent"]
    if port is not None:
        cmd += ["--port", str(port)]
    process = subprocess.Popen(
        cmd,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    lines: queue.Queue[str] = queue.Queue()

    def read(stream) -> None:  # meshcat's lines, then "" at its end
        for line in stream:
            lines.put(line)
        lines.put("")

    threading.Thread(target=read, args=(process.stdout,), daemon=True).start()
    urls: dict[str, str] = {}
    deadline = time.monotonic() + timeout
    while len(urls) < 2:
        try:
            line = lines.get(timeout=max(0.0, deadline - time.monotonic()))
        except queue.Empty:
            line = None
        if not line:
            process.kill()
            _, err = process.communicate()
            last = (err.strip().splitlines() or ["exited"])[-1]
            reason = f"no answer within {timeout:g} s" if line is None else last
            raise NNRobustError(f"the meshcat viewer did not start on {host}: {reason}")
        match = re.match(r"^(zmq_url|web_url)=(.*)$", line.strip())
        if match:
            urls[match.group(1)] = match.group(2)
    with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its own "open this URL" line
        vis = meshcat.Visualizer(zmq_url=urls["zmq_url"])
    return LiveViewer(vis, process, urls["web_url"])


if __name__ == "__main__":
    main()
