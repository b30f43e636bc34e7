#!/usr/bin/env bash
# Checks that no function of a board ELF allocates a stack frame as large as the MPU stack guard
# (`_stack_end - _stack_guard_start`, memory.x): such a frame could move the stack pointer past the guard in one
# step and write below it without touching it (src/stack_guard.rs). A function's frame is the sum of its
# `sub sp, #imm` instructions in the disassembly; a function that sets sp from a register cannot be bounded this
# way and fails the check too. Prints the five largest frames. Usage: tools/max-frame.sh ELF
# (exit status 1 when a frame reaches the guard's size or cannot be bounded, 0 otherwise)
set -euo pipefail
elf="$1"
bin="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
sym() { "$bin/llvm-nm" "$elf" | awk -v s="$1" '$3 == s { print $1 }'; }
guard=$(( 0x$(sym _stack_end) - 0x$(sym _stack_guard_start) ))
echo "stack guard: $guard bytes"
"$bin/llvm-objdump" -d -C --no-show-raw-insn "$elf" | awk -v guard="$guard" '
    function num(s,   i, c, v) {
        if (s !~ /^0x/) return s + 0
        v = 0
        for (i = 3; i <= length(s); i++) { c = index("0123456789abcdef", substr(s, i, 1)); v = v * 16 + c - 1 }
        return v
    }
    /^[0-9a-f]+ <.*>:$/ { fn = substr($0, index($0, "<") + 1); sub(/>:$/, "", fn); next }
    /\tsub(\.w|w)?\tsp, (sp, )?#/ { v = $0; sub(/^.*#/, "", v); sub(/[^0-9a-fx].*$/, "", v); frame[fn] += num(v) }
    /\t(sub(\.w)?|mov)\tsp, (sp, )?r[0-9]+/ { unbounded[fn] = 1 }
    END {
        bad = 0
        for (f in frame) if (frame[f] >= guard) { print "FRAME " frame[f] " >= guard " guard ": " f; bad = 1 }
        for (f in unbounded) { print "UNBOUNDED (sp set from a register): " f; bad = 1 }
        for (f in frame) print frame[f] "\t" f | "sort -rn | head -5"
        close("sort -rn | head -5")
        exit bad
    }'
