/* meso: surface mesostructure rendering on the CPU.
 *
 * One include for the whole public API:
 *   core.h           results, context, logging, parallel loops, progress, hashing, files
 *   math.h           vectors and matrices
 *   image.h          float images, PNG, textures
 *   sh.h             spherical harmonics of order 4 (basis, irradiance, rotation)
 *   environment.h    environment light: Radiance .hdr maps, procedural sky, sampling
 *   geom.h           meshes, shapes, import, tangents, curvature, quadrics
 *   mesostructure.h  height fields and solids
 *   bake.h           the bake file container and every baked representation
 *   scene.h          scene files
 *   render.h         framebuffers, techniques, renderers (rasterizer and reference)
 *   compare.h        metrics, difference images, sheets
 *   gl.h             the OpenGL back end (GLSL shaders, headless EGL)
 * Conventions: docs/design.md. Errors: see core.h.
 */
#ifndef MESO_MESO_H
#define MESO_MESO_H

#include "meso/core.h"
#include "meso/math.h"
#include "meso/image.h"
#include "meso/sh.h"
#include "meso/environment.h"
#include "meso/geom.h"
#include "meso/mesostructure.h"
#include "meso/bake.h"
#include "meso/scene.h"
#include "meso/render.h"
#include "meso/compare.h"
#include "meso/gl.h"

#define MESO_VERSION_STRING "0.1.0"

#endif
