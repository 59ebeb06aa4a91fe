// Test-only: a shared library with the right file name but no rsvio_plugin_entry symbol.
extern "C" __attribute__((visibility("default"))) int some_other_symbol() { return 42; }
