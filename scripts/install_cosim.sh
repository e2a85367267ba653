#!/usr/bin/env bash
# What the co-simulation tests need beyond scripts/install.sh: the other
# masters and checkers, each from its own registry.
#   PyPI:          libcosimpy (libcosim), ecospy (ecos)
#   Debian:        libtbb12 (ecos links it), a Java 17 runtime and Maven
#   Maven Central: INTO-CPS Maestro 3.1.1 (jar with dependencies) and
#                  VDMCheck2 1.1.3 (distribution-rules zip, unpacked)
# Artifacts land in build/cosim-tools/ (and ~/.m2); reruns are no-ops.
set -euo pipefail
cd "$(dirname "$0")/.."
TOOLS=build/cosim-tools
mkdir -p "$TOOLS"

missing=()
ldconfig -p 2>/dev/null | grep -q 'libtbb\.so\.12' || missing+=(libtbb12)
command -v java >/dev/null || missing+=(openjdk-17-jre-headless)
command -v mvn >/dev/null || missing+=(maven)
if [ ${#missing[@]} -gt 0 ] && command -v apt-get >/dev/null; then
  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}") >/dev/null
fi

python3 -m pip install --quiet "libcosimpy>=0.0.6" "ecospy>=0.7"

fetch() {  # fetch ARTIFACT FILE
  [ -s "$TOOLS/$2" ] && return 0
  mvn -q -B dependency:copy -Dartifact="$1" -DoutputDirectory="$TOOLS" -Dmdep.overWriteIfNewer=false >/dev/null
  [ -s "$TOOLS/$2" ]
}
fetch org.into-cps.maestro:maestro:3.1.1:jar:jar-with-dependencies maestro-3.1.1-jar-with-dependencies.jar
fetch org.into-cps.vdmcheck.fmi2:vdmcheck2:1.1.3:zip:distribution-rules vdmcheck2-1.1.3-distribution-rules.zip
if [ ! -d "$TOOLS/vdmcheck2" ]; then
  rm -rf "$TOOLS/vdmcheck2.tmp" && mkdir -p "$TOOLS/vdmcheck2.tmp"
  python3 -m zipfile -e "$TOOLS/vdmcheck2-1.1.3-distribution-rules.zip" "$TOOLS/vdmcheck2.tmp"
  chmod +x "$TOOLS"/vdmcheck2.tmp/*/VDMCheck2.sh   # zip extraction drops the execute bit the script relies on
  mv "$TOOLS/vdmcheck2.tmp" "$TOOLS/vdmcheck2"
fi
