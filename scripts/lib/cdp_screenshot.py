#!/usr/bin/python3
"""A screenshot of the live page in a running Chromium, through its DevTools protocol.

    cdp_screenshot.py DEVTOOLS_PORT OUT_PNG [URL_PREFIX]

Chromium must run with --remote-debugging-port=DEVTOOLS_PORT. Takes the first page target whose URL
starts with URL_PREFIX (any page without it) and calls Page.captureScreenshot: the page as it is live,
with its timers and decoded images (Chromium's own --screenshot mode loads the page afresh and freezes
it). Standard library only: a minimal WebSocket client (RFC 6455; text frames, client-masked).
"""
import base64
import json
import os
import socket
import struct
import sys
import urllib.parse
import urllib.request


def ws_connect(url):
    u = urllib.parse.urlparse(url)
    sock = socket.create_connection((u.hostname, u.port), timeout=30)
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall((f"GET {u.path} HTTP/1.1\r\nHost: {u.hostname}:{u.port}\r\nUpgrade: websocket\r\n"
                  f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
    head = b""
    while b"\r\n\r\n" not in head:
        chunk = sock.recv(1)
        if not chunk:
            raise RuntimeError("DevTools closed the connection during the handshake")
        head += chunk
    if b" 101 " not in head.split(b"\r\n")[0]:
        raise RuntimeError("DevTools refused the WebSocket: " + head.split(b"\r\n")[0].decode(errors="replace"))
    return sock


def recv_exact(sock, n):
    out = bytearray()
    while len(out) < n:
        chunk = sock.recv(n - len(out))
        if not chunk:
            raise RuntimeError("DevTools closed the connection")
        out += chunk
    return bytes(out)


def ws_send(sock, text):
    data = text.encode()
    mask = os.urandom(4)
    n = len(data)
    header = bytes([0x81]) + (bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack(">H", n)
                              if n < 65536 else bytes([0x80 | 127]) + struct.pack(">Q", n))
    sock.sendall(header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(data)))


def ws_recv(sock):
    message = b""
    while True:
        b0, b1 = recv_exact(sock, 2)
        n = b1 & 0x7F
        if n == 126:
            n = struct.unpack(">H", recv_exact(sock, 2))[0]
        elif n == 127:
            n = struct.unpack(">Q", recv_exact(sock, 8))[0]
        payload = recv_exact(sock, n)
        if b0 & 0x0F == 0x8:
            raise RuntimeError("DevTools closed the WebSocket")
        message += payload
        if b0 & 0x80:
            return message.decode()


def main():
    port, out_png = int(sys.argv[1]), sys.argv[2]
    prefix = sys.argv[3] if len(sys.argv) > 3 else ""
    targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json", timeout=10))
    pages = [t for t in targets if t.get("type") == "page" and t.get("url", "").startswith(prefix)]
    if not pages:
        sys.exit(f"cdp_screenshot: no page at {prefix or 'any URL'} among {[t.get('url') for t in targets]}")
    sock = ws_connect(pages[0]["webSocketDebuggerUrl"])
    ws_send(sock, json.dumps({"id": 1, "method": "Page.captureScreenshot", "params": {"format": "png"}}))
    while True:
        reply = json.loads(ws_recv(sock))
        if reply.get("id") == 1:
            break
    if "error" in reply:
        sys.exit(f"cdp_screenshot: {reply['error']}")
    with open(out_png, "wb") as f:
        f.write(base64.b64decode(reply["result"]["data"]))


if __name__ == "__main__":
    main()
