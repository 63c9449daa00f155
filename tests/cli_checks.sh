# The checks the command-line test scripts share (tests/*/*_cli_test.sh source
# this file after moving into their scratch folder): each command's output goes
# to out.txt / err.txt, and a failed check prints both and exits 1.
fail() { echo "FAIL: $*"; echo "--- stdout"; cat out.txt; echo "--- stderr"; cat err.txt; exit 1; }
# expect STATUS COMMAND...: runs it, output in out.txt / err.txt.
expect() {
  local want=$1
  shift
  "$@" >out.txt 2>err.txt
  local got=$?
  [ "$got" -eq "$want" ] || fail "exit status $got, wanted $want: $*"
}
has() { grep -qF -- "$2" "$1" || fail "$1 lacks '$2'"; }
one_line() { [ "$(wc -l <err.txt)" -eq 1 ] || fail "stderr is not one line"; }
nothing_in() { [ ! -e "$1" ] || [ -z "$(ls -A "$1")" ] || fail "$1 is not empty after a refusal"; }
