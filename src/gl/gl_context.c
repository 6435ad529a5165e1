/* The headless OpenGL 3.3 core context: EGL on Mesa's surfaceless platform (no window system,
 * no device file needed: llvmpipe draws in memory), else on the first EGL device (a GPU's
 * render node). No surface: everything is drawn into framebuffer objects.
 *
 * The display is never terminated: EGL hands the same display to every caller of the same
 * platform, so terminating it for one renderer would end the contexts of the others. Only the
 * context is destroyed. */
#include <stdio.h>
#include <string.h>

#include "gl_internal.h"
#include "meso/runtime.h"

/* The display of the surfaceless platform, else of the first device; EGL_NO_DISPLAY when the
 * client has neither extension. */
static EGLDisplay open_display(void) {
    const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!client) return EGL_NO_DISPLAY;
    bool platform_base = strstr(client, "EGL_EXT_platform_base") != NULL;
    if (platform_base && strstr(client, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay d =
            eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
        if (d != EGL_NO_DISPLAY) return d;
    }
    if (platform_base && strstr(client, "EGL_EXT_platform_device") &&
        strstr(client, "EGL_EXT_device_enumeration")) {
        EGLDeviceEXT devices[8];
        EGLint count = 0;
        if (eglQueryDevicesEXT(8, devices, &count) && count > 0)
            return eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[0], NULL);
    }
    return EGL_NO_DISPLAY;
}

meso_result gl_context_create(meso_context *ctx, gl_context *out, meso_gl_info *out_info) {
    meso_gl_info info = {0};
    memset(out, 0, sizeof *out);
    out->display = EGL_NO_DISPLAY;
    out->context = EGL_NO_CONTEXT;
    meso_result r = MESO_ERROR_UNSUPPORTED;
    /* libepoxy aborts the process when an entry point has no provider: ask first whether
     * libEGL can be loaded at all. */
    if (!epoxy_has_egl()) {
        meso_log_error(ctx, r,
                       "OpenGL: no libEGL.so.1 (install libegl1 and Mesa: "
                       "scripts/install-deps.sh)");
        goto done;
    }
    EGLDisplay display = open_display();
    EGLint major = 0, minor = 0;
    if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor)) {
        meso_log_error(ctx, r,
                       "OpenGL: no EGL display (neither Mesa's surfaceless platform nor an EGL "
                       "device; install libegl-mesa0 and libgl1-mesa-dri)");
        goto done;
    }
    info.egl = true;
    out->display = display;
    const char *extensions = eglQueryString(display, EGL_EXTENSIONS);
    bool no_config = extensions && strstr(extensions, "EGL_KHR_no_config_context");
    bool surfaceless = extensions && strstr(extensions, "EGL_KHR_surfaceless_context");
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!no_config) {
        const EGLint want[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLint count = 0;
        if (!eglChooseConfig(display, want, &config, 1, &count) || count < 1)
            config = EGL_NO_CONFIG_KHR;
    }
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 3,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 3,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    if (!surfaceless || (!no_config && config == EGL_NO_CONFIG_KHR) ||
        !eglBindAPI(EGL_OPENGL_API) ||
        (out->context = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes)) ==
            EGL_NO_CONTEXT) {
        meso_log_error(ctx, r,
                       "OpenGL: EGL %d.%d (%s) gives no OpenGL 3.3 core context without a "
                       "surface (EGL error 0x%x)",
                       major, minor, eglQueryString(display, EGL_VENDOR), eglGetError());
        goto done;
    }
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, out->context)) {
        meso_log_error(ctx, r, "OpenGL: cannot make the context current (EGL error 0x%x)",
                       eglGetError());
        goto done;
    }
    info.core33 = epoxy_is_desktop_gl() && epoxy_gl_version() >= 33;
    snprintf(info.renderer, sizeof info.renderer, "%s", (const char *)glGetString(GL_RENDERER));
    snprintf(info.version, sizeof info.version, "%s", (const char *)glGetString(GL_VERSION));
    if (!info.core33) {
        meso_log_error(ctx, r, "OpenGL: %s gives OpenGL %s, not 3.3 core", info.renderer,
                       info.version);
        goto done;
    }
    r = MESO_OK;
done:
    if (out_info) *out_info = info;
    if (r != MESO_OK) gl_context_destroy(out);
    return r;
}

meso_result gl_context_make_current(meso_context *ctx, const gl_context *gl) {
    if (eglGetCurrentContext() == gl->context) return MESO_OK;
    if (!eglMakeCurrent(gl->display, EGL_NO_SURFACE, EGL_NO_SURFACE, gl->context))
        return meso_log_error(ctx, MESO_ERROR_INTERNAL,
                              "OpenGL: cannot make the context current (EGL error 0x%x)",
                              eglGetError());
    return MESO_OK;
}

void gl_context_destroy(gl_context *gl) {
    if (gl->context != EGL_NO_CONTEXT) {
        if (eglGetCurrentContext() == gl->context)
            eglMakeCurrent(gl->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglDestroyContext(gl->display, gl->context);
    }
    gl->context = EGL_NO_CONTEXT;
    gl->display = EGL_NO_DISPLAY;
}

meso_result meso_gl_probe(meso_context *ctx, meso_gl_info *out_info) {
    gl_context gl;
    meso_result r = gl_context_create(ctx, &gl, out_info);
    if (r == MESO_OK) gl_context_destroy(&gl);
    return r;
}
