/* meso bakes: the bake file container and the baked representations of mesostructure.
 *
 * Every baked map is saved in one container (docs/bake-format.md): magic, format version, kind,
 * the parameters it was baked with (JSON text), the hash of its source, named arrays with shape
 * and type, and a checksum. Readers validate every size against the file's length before
 * allocating. Bakes are cached by the hash of source + parameters.
 *
 * The representations an application may bake, save and load have a header each, included
 * here (the techniques' own maps, horizon, min-max, summed-area, cone and isosurface, are the
 * renderer's internals: src/internal/meso):
 *   bake_file.h        the container (docs/bake-format.md) and the bake cache
 *   bake_vdm.h         view-dependent displacement maps + MVM, SVD-compressed (VDM §3)
 *   bake_layers.h      multilayer relief maps of solids and height fields (Policarpo & Oliveira §3)
 *   bake_gdm.h         generalized displacement maps of solids and height fields, SVD-compressed
 *                      (GDM §3.1, §4.1)
 *   bake_rtv.h         the radiance transfer volume, uncompressed (GDM §3.2; first step)
 */
#ifndef MESO_BAKE_H
#define MESO_BAKE_H

#include "meso/bake_file.h"
#include "meso/bake_vdm.h"
#include "meso/bake_layers.h"
#include "meso/bake_gdm.h"
#include "meso/bake_rtv.h"

#endif
