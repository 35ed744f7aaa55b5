/* pikg-gen's stand-in for PIKG's C vector header, used only when pikg-reflect reads
   a particle header that includes <pikg_vector.h> and PIKG's inc/ is not on the
   include path. The names and layouts are those PIKG's C interface documents:
   components x, y (, z, w) of the element type, no padding. */
#ifndef PIKG_GEN_COMPAT_PIKG_VECTOR_H
#define PIKG_GEN_COMPAT_PIKG_VECTOR_H
typedef struct { double x, y; } pikg_f64vec2;
typedef struct { double x, y, z; } pikg_f64vec3;
typedef struct { double x, y, z, w; } pikg_f64vec4;
typedef struct { float x, y; } pikg_f32vec2;
typedef struct { float x, y, z; } pikg_f32vec3;
typedef struct { float x, y, z, w; } pikg_f32vec4;
typedef pikg_f64vec3 pikg_f64vec;
typedef pikg_f32vec3 pikg_f32vec;
#endif
