#pragma once
#ifdef PIK_TEST_SINGLE
using real_t = float;
#else
using real_t = double;
#endif
