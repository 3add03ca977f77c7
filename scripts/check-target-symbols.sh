#!/usr/bin/env bash
# Check the symbols of a target image or library for things bare-metal seqslam must not use.
#
#   check-target-symbols.sh --nm <nm-tool> [--archive] [--allow sym1,sym2,...] <file>
#
# Every symbol (defined or undefined, raw mangled names) is matched against these rules:
#   heap          malloc & co, sbrk, operator new/new[]/delete/delete[] (_Znw* _Zna* _Zdl* _Zda*)
#   libc          stdio, abort/exit/atexit, string functions, strtol/atoi, errno, newlib's
#                 reentrancy and init machinery, assert, setjmp, syscall stubs
#   libm          the C maths library (sin, sqrt, pow, floor, ... incl. f/l variants)
#   libstdc++     anything in namespace std (_ZSt*, _ZNSt*, _ZNKSt*)
#   exceptions    __cxa_throw & co, personality routines, _Unwind_*, __cxa_atexit,
#                 __cxa_guard_* (thread-safe statics)
#   rtti          typeinfo objects and names (_ZTI*, _ZTS*)
#   soft-float    libgcc's floating-point emulation (__adddf3, __ltsf2, __fixdfsi, ...)
# The board runtime legitimately defines memcpy/memmove/memset/memcmp and
# __cxa_pure_virtual; no rule covers them.
#
# --archive (a static library such as libseqslam.a): additionally every undefined symbol
# must be defined by a member of the same archive, be one of libgcc's integer helpers
# (64-bit division, shifts, bit counting) or be named with --allow.
# --allow also exempts the named symbols from the rules above.
#
# Exit status: 0 clean (one PASS line), 1 violations (one line each), 2 usage or nm error.
set -u

usage() {
  echo "usage: $(basename "$0") --nm <nm-tool> [--archive] [--allow sym1,sym2] <file>" >&2
  exit 2
}

nm_tool=""
archive=0
allow=""
file=""
while [ $# -gt 0 ]; do
  case $1 in
    --nm) [ $# -ge 2 ] || usage; nm_tool=$2; shift 2 ;;
    --nm=*) nm_tool=${1#--nm=}; shift ;;
    --archive) archive=1; shift ;;
    --allow) [ $# -ge 2 ] || usage; allow="$allow,$2"; shift 2 ;;
    --allow=*) allow="$allow,${1#--allow=}"; shift ;;
    -h|--help) usage ;;
    -*) echo "check-target-symbols: unknown option $1" >&2; usage ;;
    *) [ -z "$file" ] || usage; file=$1; shift ;;
  esac
done
[ -n "$nm_tool" ] && [ -n "$file" ] || usage
if ! command -v "$nm_tool" >/dev/null 2>&1; then
  echo "check-target-symbols: nm tool not found: $nm_tool" >&2
  exit 2
fi
if [ ! -f "$file" ]; then
  echo "check-target-symbols: no such file: $file" >&2
  exit 2
fi

# Portable (-P) format with the file name first (-A): "<file>[<member>]: <name> <type> ...".
# --no-demangle: rules match raw names; demangled names are only for the messages.
if ! symbols=$("$nm_tool" -P -A --no-demangle "$file" 2>&1); then
  echo "check-target-symbols: $nm_tool failed on $file:" >&2
  echo "$symbols" >&2
  exit 2
fi

demangler=""
for candidate in "${nm_tool%nm}c++filt" c++filt; do
  if command -v "$candidate" >/dev/null 2>&1; then
    demangler=$candidate
    break
  fi
done

report=$(printf '%s\n' "$symbols" | awk -v archive="$archive" -v allow="$allow" '
BEGIN {
  n = split(allow, a, ",")
  for (i = 1; i <= n; i++) if (a[i] != "") allowed[a[i]] = 1

  libgcc_int = "__udivdi3 __divdi3 __umoddi3 __moddi3 __muldi3 __ashldi3 __ashrdi3 " \
               "__lshrdi3 __clzsi2 __clzdi2 __ctzsi2 __ctzdi2 __popcountsi2 __bswapsi2 " \
               "__bswapdi2"
  n = split(libgcc_int, a, " ")
  for (i = 1; i <= n; i++) libgcc[a[i]] = 1
  # -msave-restore: prologue/epilogue helpers, also libgcc (save-restore.o).
  for (i = 0; i <= 12; i++) {
    libgcc["__riscv_save_" i] = 1
    libgcc["__riscv_restore_" i] = 1
  }

  r = 0
  rule[++r] = "heap";       re[r] = "^(malloc|calloc|realloc|free|memalign|aligned_alloc|posix_memalign|valloc|pvalloc|sbrk|_sbrk|_sbrk_r|_malloc_r|_calloc_r|_realloc_r|_free_r|__malloc_lock|__malloc_unlock|_Znw.*|_Zna.*|_Zdl.*|_Zda.*)$"
  rule[++r] = "libc";       re[r] = "^(_?_?(v?(f|s|sn|as|d)?printf|v?(f|s)?scanf|v?(f|s|sn|as)?iprintf|printf_r|_printf_r|_vfprintf_r|_svfprintf_r|_vfiprintf_r)|puts|putchar|putc|fputc|fputs|fwrite|fread|fopen|fclose|fflush|fseek|ftell|getchar|getc|fgetc|fgets|abort|exit|_exit|_Exit|atexit|at_quick_exit|quick_exit|strlen|strnlen|strcmp|strncmp|strcpy|strncpy|strcat|strncat|strchr|strrchr|strstr|strdup|strndup|strtok|strtol|strtoul|strtoll|strtoull|strtod|strtof|atoi|atol|atoll|atof|itoa|errno|__errno|_errno|_impure_ptr|_global_impure_ptr|_impure_data|__libc_init_array|__libc_fini_array|_reent|_reclaim_reent|__sinit|__assert|__assert_func|__assert_fail|qsort|bsearch|rand|srand|time|clock|getenv|system|setjmp|longjmp|_setjmp|_longjmp|signal|raise|_write|_read|_open|_close|_lseek|_fstat|_isatty|_kill|_getpid|_times|_gettimeofday|_link|_unlink|_stat|_wait|_fork|_execve|__stack_chk_fail|__stack_chk_guard)$"
  rule[++r] = "libm";       re[r] = "^(sin|cos|tan|asin|acos|atan|atan2|sinh|cosh|tanh|asinh|acosh|atanh|exp|exp2|expm1|log|log2|log10|log1p|pow|sqrt|cbrt|hypot|floor|ceil|round|lround|llround|trunc|rint|lrint|nearbyint|fmod|remainder|fabs|fmin|fmax|fma|ldexp|frexp|modf|scalbn|copysign|nan|erf|erfc|tgamma|lgamma|sincos)(f|l)?$"
  rule[++r] = "libstdc++";  re[r] = "^(_ZSt|_ZNSt|_ZNKSt|_ZGVNSt)"
  rule[++r] = "exceptions"; re[r] = "^(__cxa_throw|__cxa_allocate_exception|__cxa_free_exception|__cxa_begin_catch|__cxa_end_catch|__cxa_rethrow|__cxa_call_unexpected|__cxa_get_exception_ptr|__cxa_current_exception_type|__cxa_bad_cast|__cxa_bad_typeid|__cxa_throw_bad_array_new_length|__cxa_atexit|__cxa_finalize|__cxa_thread_atexit|__cxa_guard_acquire|__cxa_guard_release|__cxa_guard_abort|__cxa_guard_.*|__gxx_personality_v0|__gcc_personality_v0|_Unwind_.*|__register_frame_info|__deregister_frame_info|_ZSt9terminatev|__dso_handle)$"
  rule[++r] = "rtti";       re[r] = "^(_ZTI|_ZTS)"
  rule[++r] = "soft-float"; re[r] = "^__((add|sub|mul|div)(hf|sf|df|tf|xf)3|neg(hf|sf|df|tf|xf)(2|3)|(eq|ne|lt|le|gt|ge|unord|cmp)(hf|sf|df|tf|xf)2|fix(uns)?(hf|sf|df|tf|xf)(si|di|ti)|float(un)?(si|di|ti)(hf|sf|df|tf|xf)|(extend|trunc)(hf|sf|df|tf|xf)(hf|sf|df|tf|xf)2|powi(hf|sf|df|tf|xf)2|(mul|div)(hc|sc|dc|tc|xc)3|abs(sf|df|tf)2)$"
  nrules = r
}
{
  # "<file>[<member>]: <name> <type> [<value> [<size>]]"; an archive also lists its members
  # ("<file>[<member>]:") and index lines, which have no type field.
  if (NF < 3 || $1 !~ /:$/) next
  name = $2; type = $3
  if (length(type) != 1) next
  total++
  undefined = (type == "U" || type == "w" || type == "v")
  if (undefined) undef[name] = 1
  else defined[name] = 1
  if (name in allowed) next
  for (i = 1; i <= nrules; i++) {
    if (name ~ re[i]) {
      kind = undefined ? "reference to" : "definition of"
      key = rule[i] SUBSEP name
      if (!(key in seen)) {
        seen[key] = 1
        print "V\t" rule[i] "\t" kind "\t" name
      }
      break
    }
  }
}
END {
  if (archive) {
    for (name in undef) {
      if (name in defined || name in libgcc || name in allowed) continue
      print "U\tunresolved\tundefined, not defined in the archive\t" name
    }
  }
  print "T\t" total + 0
}')

total=$(printf '%s\n' "$report" | awk -F'\t' '$1 == "T" { print $2 }')
violations=$(printf '%s\n' "$report" | awk -F'\t' '$1 == "V" || $1 == "U"' | sort -t$'\t' -k2,2 -k4,4)
mode=$([ $archive -eq 1 ] && echo archive || echo image)

if [ -z "$violations" ]; then
  echo "check-target-symbols: PASS: $total symbols checked in $file ($mode)"
  exit 0
fi

count=0
while IFS=$'\t' read -r _ rule kind name; do
  pretty=""
  if [ -n "$demangler" ]; then
    d=$(printf '%s\n' "$name" | "$demangler")
    [ "$d" != "$name" ] && pretty=" ($d)"
  fi
  echo "check-target-symbols: [$rule] $kind $name$pretty"
  count=$((count + 1))
done <<< "$violations"
echo "check-target-symbols: FAIL: $count violation(s) among $total symbols in $file ($mode)"
exit 1
