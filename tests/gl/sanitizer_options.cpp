// Under ORGANSIM_SANITIZE: Mesa's llvmpipe leaks a few small LLVM JIT
// allocations (~2 KB per process, realloc inside libLLVM-15) that are still
// alive when LeakSanitizer runs after the driver has been unloaded, so their
// frames show as "<unknown module>" and cannot be suppressed by name. Leak
// checking stays on for every other test executable; address and undefined-
// behaviour checks stay on here. Without the sanitizer this symbol is unused.
extern "C" const char* __asan_default_options();
extern "C" const char* __asan_default_options() { return "detect_leaks=0"; }
