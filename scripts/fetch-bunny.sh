#!/usr/bin/env bash
# Fetches the Stanford bunny and writes it as OUTDIR/bunny.obj, for tetrahedralising (e.g. the
# Table 1 body sizes). Idempotent: it does nothing when OUTDIR/bunny.obj already exists.
#
# The mesh comes from the npm package "bunny" (version 1.0.1, public domain): 1,839 positions
# and 3,674 triangles, y up, about 9.7 units tall. Unlike the original scan, whose bottom has
# holes, this version is already closed and outward-oriented, so it goes to TetGen unchanged;
# the conversion checks that (every edge in both directions once) and stops if it ever is not.
# The mesh itself is not part of the repository: fetch it into an ignored folder, e.g.
# scripts/fetch-bunny.sh out/meshes.
set -euo pipefail

if [ $# -ne 1 ]; then
  echo "usage: fetch-bunny.sh OUTDIR" >&2
  exit 2
fi
out="$1"
obj="$out/bunny.obj"
[ -f "$obj" ] && exit 0

for tool in npm node tar; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "fetch-bunny: $tool is missing; install Node.js and npm (Debian: apt-get install nodejs npm)" >&2
    exit 1
  fi
done

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack --silent bunny@1.0.1 >/dev/null && tar xzf bunny-1.0.1.tgz)

mkdir -p "$out"
node - "$tmp/package" "$obj.tmp" <<'EOF'
const fs = require("fs");
const [pkg, dest] = process.argv.slice(2);
const { positions, cells } = require(pkg);

// Closed and consistently oriented: each directed edge once, and its reverse once.
const edges = new Set();
for (const c of cells)
  for (let i = 0; i < 3; ++i) {
    const e = c[i] + " " + c[(i + 1) % 3];
    if (edges.has(e)) throw new Error("edge " + e + " is used twice in one direction");
    edges.add(e);
  }
let open = 0;
for (const e of edges) {
  const [a, b] = e.split(" ");
  if (!edges.has(b + " " + a)) ++open;
}
if (open) throw new Error("the bunny has " + open + " boundary edges; it must be closed");

const lines = ["# Stanford bunny, npm package bunny@1.0.1 (public domain); closed, y up"];
for (const p of positions) lines.push("v " + p.join(" "));
for (const c of cells) lines.push("f " + c.map((i) => i + 1).join(" "));
fs.writeFileSync(dest, lines.join("\n") + "\n");
EOF
mv "$obj.tmp" "$obj"
echo "fetch-bunny: wrote $obj"
