// The consumer's own core/options.h, first on its include path: quasiroll's
// installed headers include "quasiroll/core/options.h", never this file.
#pragma once
#error "a quasiroll header included the consumer's core/options.h"
