/* Write the procedural sky (meso_environment_create_sky) as a Radiance .hdr file: how
 * examples/sky.hdr was made (scripts/make-sky-hdr.sh builds and runs this).
 *
 *   make_sky_hdr OUT.hdr [WIDTH] [SUN_X SUN_Y SUN_Z]
 */
#include <stdio.h>
#include <stdlib.h>

#include <meso/meso.h>

int main(int argc, char **argv) {
    if (argc != 2 && argc != 3 && argc != 6) {
        fprintf(stderr, "usage: make_sky_hdr OUT.hdr [WIDTH] [SUN_X SUN_Y SUN_Z]\n");
        return 2;
    }
    meso_sky_desc sky = {0};
    if (argc >= 3) sky.width = atoi(argv[2]);
    if (argc == 6)
        sky.sun_direction =
            (meso_vec3){strtof(argv[3], NULL), strtof(argv[4], NULL), strtof(argv[5], NULL)};
    meso_context *ctx = NULL;
    if (meso_context_create(&(meso_context_desc){0}, &ctx) != MESO_OK) return 1;
    meso_environment *env = NULL;
    meso_result r = meso_environment_create_sky(ctx, &sky, 1.0f, &env);
    if (r == MESO_OK) r = meso_environment_save_hdr(ctx, env, argv[1]);
    if (r != MESO_OK) fprintf(stderr, "meso: %s\n", meso_context_last_error(ctx));
    meso_environment_destroy(env);
    meso_context_destroy(ctx);
    return r == MESO_OK ? 0 : r == MESO_ERROR_IO ? 1 : 2;
}
