#!/usr/bin/env bash
# three.js as the animation page carries it: the parts of it that entry.js names, bundled and
# minified by esbuild into animate/src/three.min.js (committed: building the page needs no
# network and no Node.js). Run again after changing entry.js or the versions in package.json:
#
#   animate/three/build.sh
set -euo pipefail
cd "$(dirname "$0")"
npm ci --no-audit --no-fund >/dev/null
version=$(node -p 'JSON.parse(require("fs").readFileSync("node_modules/three/package.json", "utf8")).version')
out=../src/three.min.js
{
    echo "// three.js $version (npm: three@$version, MIT license), the parts animate/three/entry.js names, bundled by animate/three/build.sh."
    npx esbuild entry.js --bundle --minify --format=iife --global-name=THREE --legal-comments=inline --target=es2020 --log-level=warning
} >"$out.tmp"
mv "$out.tmp" "$out"
echo "$out: $(wc -c <"$out") bytes"
