#pragma once
struct Body {
  double mass;
  vec3 pos;
};
