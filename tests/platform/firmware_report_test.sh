#!/usr/bin/env bash
# The firmware report's stack check on call graphs the real compiler writes
# (firmware_report.py --self-test feeds it a hand-written graph):
#   a planted cycle, f -> g -> f across two files, must fail as recursion;
#   a chain through two lambdas of one function must pass, each lambda named
#   apart from the function that holds it (the report once showed
#   `RecoverySearch::run -> run -> run`, which read as recursion);
#   a call to a function whose call graph is missing must fail.
# Usage: firmware_report_test.sh CXX "CPU_FLAGS" PYTHON REPORT
set -euo pipefail
cxx=${1:?} flags=${2:?} python=${3:?} report=${4:?}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
compile() {  # DIR FILE...
  local dir=$1; shift
  mkdir -p "$dir"
  for f in "$@"; do
    # shellcheck disable=SC2086
    (cd "$dir" && "$cxx" $flags -O1 -fno-inline -fcallgraph-info=su -c "$work/src/$f" -o "${f%.cpp}.o")
  done
}
mkdir -p "$work/src"
cat > "$work/src/f.cpp" <<'CPP'
int g(int n);
int f(int n) { volatile int a[4] = {n, n, n, n}; return n > 0 ? g(n - 1) + a[1] : 0; }
CPP
cat > "$work/src/g.cpp" <<'CPP'
int f(int n);
int g(int n) { return n > 0 ? f(n - 1) : 1; }
CPP
cat > "$work/src/lambdas.cpp" <<'CPP'
int leaf(int n) { volatile int a[8] = {n}; return a[0] + n; }
int outer(int n) {
  auto inner = [](int k) { volatile int b[2] = {k, k}; return leaf(k) + b[1]; };
  auto middle = [&](int k) { volatile int c[2] = {k, k}; return inner(k) + c[0]; };
  return middle(n) + 1;
}
CPP
cat > "$work/src/caller.cpp" <<'CPP'
int elsewhere(int n);
int caller(int n) { return elsewhere(n) + 1; }
CPP
status=0
compile "$work/cycle" f.cpp g.cpp
if out=$("$python" "$report" --build "$work/cycle" --stack-only); then
  echo "FAIL: a planted f -> g -> f cycle passed:"; echo "$out"; status=1
elif ! grep -q "FAIL: recursion through" <<< "$out"; then
  echo "FAIL: the cycle failed for another reason:"; echo "$out"; status=1
else
  echo "planted cycle: caught ($(grep -m1 'recursion through' <<< "$out"))"
fi
compile "$work/lambdas" lambdas.cpp
if ! out=$("$python" "$report" --build "$work/lambdas" --stack-only); then
  echo "FAIL: a chain through two lambdas failed:"; echo "$out"; status=1
elif ! grep -q "outer → outer::<lambda at lambdas.cpp:4> → outer::<lambda at lambdas.cpp:3> → leaf" <<< "$out"; then
  echo "FAIL: the lambdas are not named apart:"; echo "$out"; status=1
else
  echo "lambdas: $(grep '^outer:' <<< "$out")"
fi
compile "$work/missing" caller.cpp
if out=$("$python" "$report" --build "$work/missing" --stack-only); then
  echo "FAIL: a call with no call graph passed:"; echo "$out"; status=1
else
  echo "missing call graph: caught ($(grep -m1 'no call graph' <<< "$out"))"
fi
[ "$status" = 0 ] && echo PASS
exit $status
