#!/usr/bin/env bash
# Renders an HTML page in headless Chromium and checks it as a reader would see it:
#   .ci/browser-check.sh PAGE.html OUT.png [TEXT ...]
# - every <img src> of the page names a file that exists beside it, and Chromium's log has
#   no "Failed to load resource", and every image decodes (PNG chunks and pixel data, SVG XML);
# - no console message (the pages have no scripts: Chromium logs console messages as
#   "CONSOLE" lines);
# - the rendered DOM holds at least one <table> and every TEXT given (e.g. section headings);
# - the screenshot OUT.png is written and not blank.
# Generic: any self-contained page (meid report, meid paper). Needs `chromium` on PATH
# (Debian's package; .ci/run installs it). Exit 1 with the reason on any failure.
set -euo pipefail

page=${1:?usage: browser-check.sh PAGE.html OUT.png [TEXT ...]}
out=${2:?usage: browser-check.sh PAGE.html OUT.png [TEXT ...]}
shift 2
browser=${CHROMIUM:-}
if [ -z "$browser" ]; then
  for b in chromium chromium-browser google-chrome; do
    if command -v "$b" >/dev/null 2>&1; then browser=$b; break; fi
  done
fi
if [ -z "$browser" ]; then
  echo "browser-check: no chromium on PATH (install Debian's chromium: apt-get install -y chromium)" >&2
  exit 1
fi
[ -f "$page" ] || { echo "browser-check: $page: no such file" >&2; exit 1; }
abs=$(cd "$(dirname "$page")" && pwd)/$(basename "$page")
dir=$(dirname "$abs")
mkdir -p "$(dirname "$out")"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "browser-check: $abs: $*" >&2; exit 1; }

flags=(--headless --no-sandbox --disable-gpu --enable-logging=stderr --v=0
       --user-data-dir="$work/profile" --no-first-run --hide-scrollbars
       --window-size=1400,3000)
# A hung browser must not hang CI.
timeout 120 "$browser" "${flags[@]}" --dump-dom "file://$abs" >"$work/dom.html" 2>"$work/dom.log" ||
  fail "chromium --dump-dom failed: $(tail -5 "$work/dom.log")"
timeout 120 "$browser" "${flags[@]}" --screenshot="$work/shot.png" "file://$abs" >/dev/null 2>"$work/shot.log" ||
  fail "chromium --screenshot failed: $(tail -5 "$work/shot.log")"
cp "$work/shot.png" "$out"

# 1. Load errors and console messages in either run. The pages have no scripts, so any
#    console message (Chromium logs them as "CONSOLE" lines) is the browser complaining.
if grep -h "Failed to load resource\|net::ERR_\|CONSOLE" "$work/dom.log" "$work/shot.log"; then
  fail "a resource failed to load or the console reported (lines above)"
fi

# 2. Every image the rendered page shows is a relative file beside it that decodes: a PNG
#    whose chunks' CRCs hold and whose pixel data inflates to height x (1 + row bytes), or an
#    SVG that parses as XML with an <svg> root. (Chromium does not log a missing file:// image,
#    so this is checked on the files the rendered DOM names.)
grep -o '<img [^>]*src="[^"]*"' "$work/dom.html" | sed 's/.*src="\([^"]*\)"/\1/' >"$work/imgs" || true
n_fig=$(grep -o '<figure' "$work/dom.html" | wc -l)
count=$(wc -l <"$work/imgs")
[ "$count" -ge "$n_fig" ] || fail "$n_fig figures but $count images"
python3 - "$dir" "$work/imgs" <<'PY' || fail "an image did not load (above)"
import os, struct, sys, zlib
import xml.etree.ElementTree as ET
from urllib.parse import unquote
root, listing = sys.argv[1], sys.argv[2]
bad = 0
for src in open(listing).read().split("\n"):
    if not src:
        continue
    src = unquote(src.replace("&amp;", "&"))
    if "://" in src or src.startswith("/") or ".." in src.split("/"):
        print(f"image {src}: not a relative file inside the page's directory"); bad += 1; continue
    path = os.path.join(root, src)
    try:
        data = open(path, "rb").read()
        if src.endswith(".svg"):
            assert ET.fromstring(data).tag.endswith("svg"), "root is not <svg>"
            continue
        assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
        pos, idat = 8, b""
        while pos < len(data):
            n, kind = struct.unpack(">I4s", data[pos:pos + 8])
            body = data[pos + 8:pos + 8 + n]
            (crc,) = struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])
            assert zlib.crc32(kind + body) == crc, f"bad CRC in {kind!r}"
            if kind == b"IHDR":
                w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            elif kind == b"IDAT":
                idat += body
            pos += 12 + n
        channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}[ctype]
        row = (w * channels * depth + 7) // 8
        assert len(zlib.decompress(idat)) == h * (1 + row), "pixel data truncated"
    except Exception as e:
        print(f"image {src}: {e}"); bad += 1
sys.exit(1 if bad else 0)
PY

# 3. The page shows a table and the texts asked for.
grep -q '<table' "$work/dom.html" || fail "no <table> in the rendered page"
for text in "$@"; do
  grep -qF -- "$text" "$work/dom.html" || fail "the rendered page lacks \"$text\""
done

# 4. The screenshot is not blank: its filtered scanlines hold more than 16 distinct byte
#    values (a uniform page gives a handful).
python3 - "$out" <<'PY' || fail "the screenshot is blank"
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
pos, idat, w = 8, b"", 0
while pos < len(data):
    n, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + n]
    if kind == b"IHDR":
        w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
    elif kind == b"IDAT":
        idat += body
    pos += 12 + n
raw = zlib.decompress(idat)
# Distinct byte values over the filtered scanlines: a blank page gives a handful.
distinct = len(set(raw[:: max(1, len(raw) // 200000)]))
sys.exit(0 if distinct > 16 else 1)
PY
echo "browser-check: $abs: $count images loaded, no console error, table shown; screenshot $out"
