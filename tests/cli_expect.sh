# cli_expect.sh: the assertions the command-line test scripts share
# (sourced): run a command keeping its exit code and output, count checks
# and failures. The script reports "$checks checks, $failures failures"
# and exits non-zero when there were failures.
failures=0
checks=0
fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}

# run CMD...: runs it, keeping exit code, stdout and stderr.
run() {
    "$@" >stdout.txt 2>stderr.txt
    rc=$?
    out=$(cat stdout.txt)
    err=$(cat stderr.txt)
}
expect_rc() {  # CODE WHAT
    checks=$((checks + 1))
    [ "$rc" -eq "$1" ] || fail "$2: exit code $rc, expected $1; stderr was: $err"
}
expect_eq() {  # ACTUAL EXPECTED WHAT
    checks=$((checks + 1))
    [ "$1" == "$2" ] || fail "$3:"$'\n'"--- got:"$'\n'"$1"$'\n'"--- expected:"$'\n'"$2"
}
