#!/bin/sh
# Cross-check of the published fits against bbm itself (compiled), see README.md.
#   scripts/bbm_check/run.sh BBM_DIR [BUILD_DIR]
# BBM_DIR: a checkout of https://github.com/bsdfbenchmark/bbm (commit 9807fb3 read here).
# Builds two programs (a few minutes each: bbm is templates): evalfit with bbm as it is,
# and evalfit-full with NganHe's series summed until every channel's terms are negligible
# (bbm stops at the first channel's) and 60 Newton steps and 400 terms (bbm: 4 and 64);
# then compares plausible.material(name, fit).eval with both for every fit of every set.
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
BBM=$(cd "$1" && pwd)
OUT=${2:-build/bbm_check}
PY=${PYTHON:-python}
mkdir -p "$OUT/inc" "$OUT/full/bsdfmodel"
cp "$HERE/bbm_bsdfmodels.h" "$OUT/inc/"
sed 's/converged |= (bbm::hmin(term) < Constants::Epsilon()) \&\& (bbm::hmin(term) < bbm::hmin(last));/converged |= (bbm::hmax(term) < Constants::Epsilon()) \&\& (bbm::hmax(term) < bbm::hmax(last));/' \
    "$BBM/include/bsdfmodel/he.h" > "$OUT/full/bsdfmodel/he.h"
sed 's/he_eq78::Westin, 4, 64, true, 18>/he_eq78::Westin, 60, 400, true, 18>/' \
    "$BBM/include/bsdfmodel/ngan.h" > "$OUT/full/bsdfmodel/ngan.h"
grep -q "hmax(term) < Constants::Epsilon()" "$OUT/full/bsdfmodel/he.h"
grep -q "Westin, 60, 400, true, 18>" "$OUT/full/bsdfmodel/ngan.h"
FLAGS="-std=gnu++20 -O2 -Wno-attributes -Wfatal-errors -DBBM_BACKBONE=native -DBBM_BSDF_ENABLE_FORWARD -DBBM_NAME=bbm -DBBM_STRING_BSDF_IMPORTER -DBBM_VERSION=0.5.1"
INC="-I$OUT/inc -I$BBM/backbone/native/include -I$BBM/include"
[ -x "$OUT/evalfit" ] || ${CXX:-g++} $FLAGS $INC "$HERE/evalfit.cpp" -o "$OUT/evalfit"
[ -x "$OUT/evalfit-full" ] || ${CXX:-g++} $FLAGS -I"$OUT/inc" -I"$OUT/full" -I"$BBM/backbone/native/include" -I"$BBM/include" \
    "$HERE/evalfit.cpp" -o "$OUT/evalfit-full"
"$PY" "$HERE/compare.py" "$BBM/fits" "$OUT"
