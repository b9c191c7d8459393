// What LeakSanitizer ignores in the demo programs and the tests that render (read only by the sanitizer
// runtime; harmless otherwise). Each entry is a system library's own allocation kept until exit, never ours:
//  - Mesa's OSMesa keeps a few small framebuffer records after OSMesaDestroyContext (848 bytes per process,
//    made inside OSMesaMakeCurrent);
//  - PLplot's cairo driver loads fonts through fontconfig and its drivers through libltdl, whose caches live
//    until exit.
extern "C" const char* __lsan_default_suppressions() {
  return "leak:libOSMesa.so\n"
         "leak:libfontconfig.so\n"
         "leak:libltdl.so\n";
}
