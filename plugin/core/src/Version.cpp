#include "cape/core/Version.h"

namespace cape {

const char* version() {
  return CAPE_VERSION_STRING;
}

}  // namespace cape
