#!/usr/bin/env bash
# Render a report.html in headless Chromium (Debian's `chromium`, installed with apt-get when absent):
# fail on any console error or, at 1280 and 800 px, on a page wider than the window or a table
# cell that breaks a word; write screenshots as test artifacts: a desktop window 1280 px wide
# (SCREENSHOT.png) and a narrow one 800 px wide (SCREENSHOT-800.png).
#
#   tests/browser.sh [REPORT.html] [SCREENSHOT.png]
#
# Defaults: the fixture report written by `cargo test --test report` and target/report-screenshot.png.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${CARGO_TARGET_DIR:-target}"
html="${1:-$target/tmp/report-fixture/report.html}"
shot="${2:-$target/report-screenshot.png}"
[ -f "$html" ] || { echo "error: $html not found; run \`cargo test --test report\` or pass a report.html" >&2; exit 2; }

browser="$(command -v chromium || command -v chromium-browser || true)"
if [ -z "$browser" ]; then
  echo "chromium not found; installing Debian's chromium" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq chromium >/dev/null
  browser="$(command -v chromium)"
fi

profile="$(mktemp -d)"
log="$(mktemp)"
trap 'rm -rf "$profile" "$log"' EXIT
mkdir -p "$(dirname "$shot")"
url="file://$(realpath "$html")"
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run
       --disable-background-networking --disable-component-update --disable-sync
       --user-data-dir="$profile" --enable-logging=stderr --v=0 --hide-scrollbars)

# the page's DOM after load: proves it parsed and rendered its figures
dom="$("$browser" "${flags[@]}" --dump-dom "$url" 2>>"$log")"
n_svg="$(grep -o '<svg' <<<"$dom" | wc -l)"
narrow="${shot%.png}-800.png"
"$browser" "${flags[@]}" --window-size=1280,2400 --screenshot="$shot" "$url" 2>>"$log" >/dev/null
"$browser" "${flags[@]}" --window-size=800,2400 --screenshot="$narrow" "$url" 2>>"$log" >/dev/null

# the layout at 1280 and 800 px, measured in the page by a copy of it with a probe script added (the
# report itself has no script): the page is no wider than the window (a wide table scrolls in
# its own box), and no word of a table cell is split across two lines (a break after a hyphen,
# as in held-out, is a break between words)
probe="$profile/probe.html"
script='<script>addEventListener("load",()=>{let broken=[];for(const c of document.querySelectorAll("td,th")){const w=document.createTreeWalker(c,NodeFilter.SHOW_TEXT);for(let n=w.nextNode();n;n=w.nextNode()){const re=/[^\s-]+-?/g;let m;while((m=re.exec(n.data))){const r=document.createRange();r.setStart(n,m.index);r.setEnd(n,m.index+m[0].length);const tops=new Set([...r.getClientRects()].map(q=>Math.round(q.top)));if(tops.size>1)broken.push(m[0]);}}}const over=document.documentElement.scrollWidth-innerWidth;document.body.setAttribute("data-probe","width="+innerWidth+" overflow="+over+" broken="+broken.length+" "+broken.slice(0,5).join(" "));});</script>'
{ cat "$html"; printf '%s\n' "$script"; } > "$probe"
for width in 1280 800; do
  result="$("$browser" "${flags[@]}" --window-size=$width,2400 --dump-dom "file://$probe" 2>/dev/null | grep -o 'data-probe="[^"]*"' || true)"
  echo "layout at $width px: ${result:-no probe result}"
  case "$result" in
    *"overflow=0 broken=0 "*|*"overflow=-"*" broken=0 "*) ;;
    *) echo "FAIL: at $width px the page is wider than the window or a table cell breaks a word: $result" >&2; exit 1 ;;
  esac
done

if grep -E "Uncaught|ERROR:CONSOLE" "$log" >&2; then
  echo "FAIL: console errors while rendering $html" >&2
  exit 1
fi
for f in "$shot" "$narrow"; do
  [ -s "$f" ] || { echo "FAIL: no screenshot written to $f" >&2; exit 1; }
done
[ "$n_svg" -gt 0 ] || { echo "FAIL: the rendered page has no inline SVG figure" >&2; exit 1; }
echo "ok: $html rendered with no console errors, $n_svg inline figures; screenshots $shot, $narrow"
