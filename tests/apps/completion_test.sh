#!/usr/bin/env bash
# The bash completion generated from the option declarations (build/apps/medspring.bash) completes the
# commands, a command's options, build's kinds and a kind's options, and an option's values, in a plain
# `bash -c` with COMP_WORDS / COMP_CWORD set as bash sets them.
#   completion_test.sh SCRIPT
set -u
script=$1
[ -f "$script" ] || { echo "no completion script at $script (target medspring_completion)"; exit 1; }
complete_words() {  # WORD... : the last one is the word being completed
  bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$((${#COMP_WORDS[@]} - 1)); _medspring
           printf "%s\n" "${COMPREPLY[@]}"' _ "$script" "$@"
}
fail=0
expect() {  # WANT WORD...: WANT is among the completions
  local want=$1 got
  shift
  got=$(complete_words "$@")
  if ! grep -qx -- "$want" <<<"$got"; then
    echo "FAIL: '$*' should complete to $want; got: $(echo $got)"
    fail=1
  fi
}
expect_not() {  # UNWANTED WORD...
  local unwanted=$1 got
  shift
  got=$(complete_words "$@")
  if grep -qx -- "$unwanted" <<<"$got"; then
    echo "FAIL: '$*' should not complete to $unwanted; got: $(echo $got)"
    fail=1
  fi
}
expect run medspring ru
expect paper medspring pa
expect build medspring ""
expect_not completion medspring comp  # hidden
expect_not --out medspring ""         # a command first
expect --checkpoint-every medspring run scene.json --che
expect --checkpoint medspring run scene.json --che
expect --static-curve medspring run --out x --st
expect_not --filter medspring run --f  # bench's, not run's
expect --filter medspring bench --f
expect --no-bullet medspring bench --compare --no
expect vessel medspring build ve
expect --blend-spacing medspring build vessel --bl
expect --close-holes medspring build kidney --cl
expect_not --close-holes medspring build vessel --cl
expect cm medspring info f.obj --unit c
expect dijkstra medspring build kidney --path d
expect_not --json medspring run --threads --j  # the value of --threads: a number, nothing offered
expect run medspring help r
[ $fail -eq 0 ] && echo "bash completion: all cases pass"
exit $fail
