#!/usr/bin/env bash
# The documentation: (1) the site builds in strict mode (mkdocs.yml, docs/) without a warning: every page
# of the nav exists, every page is in the nav, every link between pages resolves, and every #anchor a
# page links to is a heading of its target; (2) no file of the repository refers to anything outside it
# (the internal notes in ../shared/); (3) every relative link of README.md names a file that exists.
# Usage: test_docs.sh SOURCE_DIR [MKDOCS]   (MKDOCS: default mkdocs on PATH; absent: skipped, exit 77)
set -u
SRC="$1" MKDOCS="${2:-mkdocs}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad

if ! command -v "$MKDOCS" > /dev/null; then
  echo "docs: skipped: mkdocs is not installed (Debian: apt-get install mkdocs mkdocs-material; scripts/install-deps installs them)"
  exit 77
fi

# (1) The site, strict, into a temporary directory. mkdocs prints WARNING lines (coloured, even into a
# file) for what strict mode turns into a failure; any such line fails here too (Python's
# DeprecationWarnings from its libraries are logged as INFO and are not ours).
if (cd "$SRC" && "$MKDOCS" build --strict --config-file mkdocs.yml --site-dir "$work/site") > "$work/mkdocs.log" 2>&1; then ok
else bad "mkdocs build --strict failed: $(grep -E 'WARNING|ERROR|Error' "$work/mkdocs.log" | head -5)"; fi
if grep -qE '(WARNING|ERROR) +-' "$work/mkdocs.log"; then bad "mkdocs warned: $(grep -E '(WARNING|ERROR) +-' "$work/mkdocs.log" | head -5)"; else ok; fi
# Every page of docs/ is in the nav, and every page of the nav is in docs/ (mkdocs 1.4 only mentions a
# page left out of the nav, as INFO).
nav="$(grep -oE '^ *- [^:]+: *[^ ]+\.md *$' "$SRC/mkdocs.yml" | sed -E 's/.*: *//; s/ *$//' | sort)"
pages="$(cd "$SRC/docs" && find . -name '*.md' | sed 's#^\./##' | sort)"
[ "$nav" = "$pages" ] && ok || bad "mkdocs.yml's nav and docs/ differ: $(diff <(echo "$nav") <(echo "$pages") | grep '^[<>]' | tr '\n' ' ')"
[ -f "$work/site/index.html" ] && ok || bad "the site has no index.html"
# Anchors: mkdocs 1.4 checks that a linked page exists, not the #fragment; every href="PAGE.html#id" (or
# "#id") of a page must name an id of its target page.
if command -v python3 > /dev/null; then
  python3 - "$work/site" > "$work/anchors.log" 2>&1 <<'PY' && ok || bad "links to missing anchors: $(head -5 "$work/anchors.log")"
import pathlib, re, sys
site = pathlib.Path(sys.argv[1])
ids = {p: set(re.findall(r'\bid="([^"]+)"', p.read_text(encoding="utf-8"))) for p in site.rglob("*.html")}
missing = []
for page, _ in ids.items():
    for href in re.findall(r'\bhref="([^"#:]*)#([^"]+)"', page.read_text(encoding="utf-8")):
        target = (page.parent / href[0]).resolve() if href[0] else page
        if target in ids and href[1] not in ids[target]:
            missing.append(f"{page.relative_to(site)} -> {href[0] or '(itself)'}#{href[1]}")
print("\n".join(missing))
sys.exit(1 if missing else 0)
PY
fi
# Nothing loaded from the network: no script, stylesheet or font from another host.
if grep -rhoE '<(script|link)[^>]*(src|href)="(https?:)?//[^"]*"' "$work/site" --include='*.html' | grep -v 'rel="canonical"' > "$work/remote.log"; then
  bad "the site loads from the network: $(sort -u "$work/remote.log" | head -3)"
else ok; fi

# (2) No reference outside the repository: the notes in ../shared/ are not part of it. Every tracked file
# (every file below SOURCE_DIR outside build/ and node_modules/ where it is not a git checkout) but this test.
if git -C "$SRC" rev-parse --is-inside-work-tree > /dev/null 2>&1; then
  (cd "$SRC" && git ls-files -z) > "$work/files"
else
  (cd "$SRC" && find . -type f -not -path './build/*' -not -path '*/node_modules/*' -not -path './.git/*' -print0) > "$work/files"
fi
if (cd "$SRC" && xargs -0 grep -nIE '\.\./shared|shared/(DESIGN|MATH|PAPER_CODE)|(^|[^/.a-z])(DESIGN|MATH|PAPER_CODE)\.md' -- < "$work/files" |
    grep -v '^\(\./\)\?tests/apps/test_docs\.sh:') > "$work/shared.log"; then
  bad "references outside the repository: $(head -5 "$work/shared.log")"
else ok; fi

# (3) README.md's relative links (Markdown links and images; a #fragment is dropped) name files that exist.
broken=""
while IFS= read -r target; do
  case "$target" in http://* | https://* | mailto:* | '#'*) continue ;; esac
  path="${target%%#*}"
  [ -e "$SRC/$path" ] || broken+=" $target"
done < <(grep -oE '\]\([^)[:space:]]+' "$SRC/README.md" | sed 's/^](//')
[ -z "$broken" ] && ok || bad "README.md links to missing files:$broken"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
