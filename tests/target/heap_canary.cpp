// Must NOT link: proves that the no-heap link options reject heap use in firmware code.
// tests/target/CMakeLists.txt builds it expecting the linker to name the wrapped symbol.
#include <cstdlib>

#if defined(KINCAL_CANARY_MALLOC)
extern "C" [[noreturn]] void firmware_main() {
  void* volatile p = std::malloc(16);
  std::free(p);
  for (;;) {
  }
}
#elif defined(KINCAL_CANARY_NEW)
extern "C" [[noreturn]] void firmware_main() {
  int* volatile p = new int(3);
  delete p;
  for (;;) {
  }
}
#endif
