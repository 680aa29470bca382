#!/usr/bin/env python3
"""e2e: report.html in a real browser. Debian's headless Chromium, driven through ChromeDriver's
W3C WebDriver HTTP API (standard library only), loads the page from disk (offline), every
image must have decoded, and a screenshot of the page must not be blank.

usage: report_browser.py REPORT.html SCREENSHOT.png
exit 77 (skipped) when chromium or chromedriver is not installed (scripts/install-deps.sh installs them).
"""
import base64, html, json, os, re, shutil, socket, subprocess, sys, time, urllib.parse, urllib.request, zlib


def fail(msg):
    print("FAIL: " + msg, file=sys.stderr)
    sys.exit(1)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def call(base, method, path, body=None, timeout=60):
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(base + path, data=data, method=method, headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=timeout) as r:
        return json.loads(r.read())["value"]


def decode_png(data):
    """8-bit RGB/RGBA PNG → (width, height, channels, rows of bytes)."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail("screenshot is not a PNG")
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length = int.from_bytes(data[pos:pos + 4], "big")
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, ctype = int.from_bytes(body[0:4], "big"), int.from_bytes(body[4:8], "big"), body[8], body[9]
            if depth != 8 or ctype not in (2, 6):
                fail("unexpected screenshot PNG (depth %d, colour type %d)" % (depth, ctype))
            channels = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, stride, rows, prev = zlib.decompress(idat), width * channels, [], bytearray(width * channels)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b, c = prev[i], prev[i - channels] if i >= channels else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return width, height, channels, rows


def main():
    report, shot = os.path.abspath(sys.argv[1]), sys.argv[2]
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    if not chromium or not driver:
        print("SKIP: chromium and chromedriver are needed (scripts/install-deps.sh installs them)")
        sys.exit(77)
    if not os.path.isfile(report):
        fail("%s: no report" % report)

    # Self-contained: every src/href is a relative file that exists (nothing fetched from the net).
    page = open(report, encoding="utf-8").read()
    refs = re.findall(r'(?:src|href)="([^"]+)"', page)
    for ref in refs:
        if re.match(r"^([A-Za-z][A-Za-z0-9+.-]*:|//)", ref):
            fail("report refers to %s: it must open offline" % ref)
        ref = urllib.parse.unquote(html.unescape(ref))
        if not os.path.isfile(os.path.join(os.path.dirname(report), ref)):
            fail("report refers to %s, which is not there" % ref)

    port = free_port()
    proc = subprocess.Popen([driver, "--port=%d" % port], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    base = "http://127.0.0.1:%d" % port
    try:
        for _ in range(100):
            try:
                call(base, "GET", "/status", timeout=2)
                break
            except Exception:
                time.sleep(0.1)
        else:
            fail("chromedriver did not answer on port %d within 10 s" % port)
        caps = {"capabilities": {"alwaysMatch": {"browserName": "chrome", "goog:chromeOptions": {
            "binary": chromium,
            "args": ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                     "--window-size=1400,1800", "--allow-file-access-from-files"]}}}}
        sid = call(base, "POST", "/session", caps)["sessionId"]
        try:
            call(base, "POST", "/session/%s/url" % sid, {"url": "file://" + report})
            for _ in range(100):
                state = call(base, "POST", "/session/%s/execute/sync" % sid,
                             {"script": "return document.readyState", "args": []})
                if state == "complete":
                    break
                time.sleep(0.1)
            else:
                fail("the page did not finish loading within 10 s")
            images = call(base, "POST", "/session/%s/execute/sync" % sid, {"script": """
                return Array.from(document.images).map(i => ({src: i.getAttribute('src'), complete: i.complete,
                                                              w: i.naturalWidth, h: i.naturalHeight}));""", "args": []})
            svgs = call(base, "POST", "/session/%s/execute/sync" % sid,
                        {"script": "return document.querySelectorAll('svg').length", "args": []})
            title = call(base, "GET", "/session/%s/title" % sid)
            png = base64.b64decode(call(base, "GET", "/session/%s/screenshot" % sid))
        finally:
            call(base, "DELETE", "/session/%s" % sid)
    finally:
        proc.terminate()
        proc.wait(timeout=10)

    if not title.startswith("scan2cad report"):
        fail("page title %r" % title)
    if len(images) < 8:
        fail("only %d images on the page" % len(images))
    broken = [i["src"] for i in images if not i["complete"] or i["w"] == 0 or i["h"] == 0]
    if broken:
        fail("broken images in the browser: %s" % broken)
    with open(shot, "wb") as f:
        f.write(png)
    width, height, channels, rows = decode_png(png)
    colours, dark = set(), 0
    for row in rows[::4]:
        for x in range(0, width * channels, channels * 4):
            px = bytes(row[x:x + 3])
            colours.add(px)
            dark += sum(px) < 600
    sampled = len(rows[::4]) * len(range(0, width * channels, channels * 4))
    if len(colours) < 50 or dark < 0.05 * sampled:
        fail("the screenshot looks blank (%d colours, %d of %d samples not near-white)" % (len(colours), dark, sampled))
    print("report in Chromium: %d images decoded (%s), %d charts, screenshot %dx%d with %d colours -> %s"
          % (len(images), ", ".join("%dx%d" % (i["w"], i["h"]) for i in images[:2]) + ", ...", svgs, width, height,
             len(colours), shot))


if __name__ == "__main__":
    main()
