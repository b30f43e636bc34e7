#!/usr/bin/env bash
# Lists the functions of a board ELF that can reach the panic handler: every function with a direct call or
# branch into core's panic entry points (`core::panicking::*`, the `unwrap_failed` / `expect_failed` /
# index-failure helpers), found by walking the disassembly's call graph backwards from the panic handler.
# Used by `.ci/run` when the no-panic proof fails to link, on the same configuration built with the ordinary
# handler. Usage: tools/panic-paths.sh ELF   (exit status 1 when any path exists, 0 when none)
set -euo pipefail
elf="$1"
bin="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
"$bin/llvm-objdump" -d -C --no-show-raw-insn "$elf" | awk '
    # function headers: "0000abcd <name>:"
    /^[0-9a-f]+ <.*>:$/ { fn = substr($0, index($0, "<") + 1); sub(/>:$/, "", fn); next }
    # branches with a symbolic target: "bl 0x... <target>" (also b, b.w, bcc.w ... tail calls)
    /\t(bl|blx|b|b\.w|b[a-z][a-z]\.w|b[a-z][a-z])\t0x[0-9a-f]+ <[^>]*>/ {
        t = $0; sub(/^.*\t0x[0-9a-f]+ </, "", t); sub(/>.*$/, "", t); sub(/\+0x[0-9a-f]+$/, "", t)
        if (t != fn) edge[t] = edge[t] SUBSEP fn
    }
    END {
        # roots: the panic handler and core panic machinery
        for (t in edge) if (t ~ /rust_begin_unwind|^core::panicking::|unwrap_failed|expect_failed|index_len_fail|index_order_fail|slice_index_fail|slice_error_fail|panic_bounds_check|panic_const|panic_already_|panic_on_ord_violation/) { reach[t] = 1; queue[n++] = t }
        for (i = 0; i < n; i++) {
            split(edge[queue[i]], callers, SUBSEP)
            for (c in callers) if (callers[c] != "" && !(callers[c] in reach)) { reach[callers[c]] = 1; queue[n++] = callers[c] }
        }
        found = 0
        for (f in reach) if (f !~ /^(core::|__rustc::|<core::|compiler_builtins)/) {
            # only the functions that call into core directly: the roots of each path in our code or our deps
            direct = ""
            for (t in edge) if (reach[t] && t ~ /^(core::|__rustc::|<core::)/) { if (index(edge[t] SUBSEP, SUBSEP f SUBSEP)) direct = direct " " t }
            if (direct != "") { print f "  ->" direct; found = 1 }
        }
        exit found
    }' | sort
