/* The viewer's window-free logic (app/view_state.c, app/view_script.c): camera maths against
 * closed forms, the bindings, what actions do to the state, adaptive resolution, the event
 * script's grammar and its errors. No SDL, no window. */
#include <math.h>
#include <string.h>

#include "test_util.h"
#include "view_script.h"
#include "view_state.h"

#define PI 3.14159265358979323846

static double distance(view_vec3 a, view_vec3 b) {
    return sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
}

static void assert_vec3_near(view_vec3 a, view_vec3 b, double tolerance) {
    if (distance(a, b) > tolerance)
        fail_msg("(%.9g, %.9g, %.9g) != (%.9g, %.9g, %.9g)", a.x, a.y, a.z, b.x, b.y, b.z);
}

static view_camera camera_on_z(void) { return (view_camera){{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 40}; }

static void test_view_orbit_yaw_turns_about_up_keeping_distance(void **state) {
    (void)state;
    view_camera c = camera_on_z();
    view_camera_orbit(&c, 90.0, 0.0);
    /* +90 degrees about +y (right-handed) takes +z to +x */
    assert_vec3_near(c.eye, (view_vec3){2, 0, 0}, 1e-12);
    assert_vec3_near(c.target, (view_vec3){0, 0, 0}, 0.0);
    for (int i = 0; i < 3; i++) view_camera_orbit(&c, 90.0, 0.0);
    assert_vec3_near(c.eye, (view_vec3){0, 0, 2}, 1e-12);
}

static void test_view_orbit_pitch_raises_the_eye_and_stops_before_the_pole(void **state) {
    (void)state;
    view_camera c = camera_on_z();
    view_camera_orbit(&c, 0.0, 30.0);
    assert_vec3_near(c.eye, (view_vec3){0, 2 * sin(PI / 6), 2 * cos(PI / 6)}, 1e-12);
    view_camera_orbit(&c, 0.0, 500.0); /* far past the pole: held 1 degree short of it */
    double polar = acos(c.eye.y / 2.0) * 180.0 / PI;
    assert_true(fabs(polar - 1.0) < 1e-9);
    assert_true(fabs(distance(c.eye, c.target) - 2.0) < 1e-12);
    view_camera_orbit(&c, 0.0, -500.0);
    polar = acos(c.eye.y / 2.0) * 180.0 / PI;
    assert_true(fabs(polar - 179.0) < 1e-9);
}

static void test_view_pan_moves_eye_and_target_by_the_view_height(void **state) {
    (void)state;
    view_camera c = camera_on_z();
    /* dragging the whole viewport height moves by the view's height at the target's depth */
    view_camera_pan(&c, 0.0, 600.0, 600);
    double height = 2.0 * 2.0 * tan(20.0 * PI / 180.0);
    assert_vec3_near(c.target, (view_vec3){0, height, 0}, 1e-12);
    assert_vec3_near(c.eye, (view_vec3){0, height, 2}, 1e-12);
    view_camera_pan(&c, 300.0, 0.0, 600); /* dragging right moves the camera left */
    assert_vec3_near(c.target, (view_vec3){-height / 2, height, 0}, 1e-12);
}

static void test_view_zoom_steps_ten_percent_within_limits(void **state) {
    (void)state;
    view_camera c = camera_on_z();
    view_camera_zoom(&c, 1.0, 0.1, 10.0);
    assert_vec3_near(c.eye, (view_vec3){0, 0, 1.8}, 1e-12);
    view_camera_zoom(&c, -2.0, 0.1, 10.0);
    assert_vec3_near(c.eye, (view_vec3){0, 0, 1.8 / 0.81}, 1e-12);
    view_camera_zoom(&c, 1000.0, 0.1, 10.0);
    assert_vec3_near(c.eye, (view_vec3){0, 0, 0.1}, 1e-12);
    view_camera_zoom(&c, -1000.0, 0.1, 10.0);
    assert_vec3_near(c.eye, (view_vec3){0, 0, 10.0}, 1e-12);
}

static void test_view_turntable_frame_zero_is_home_and_keeps_height(void **state) {
    (void)state;
    view_camera home = {{0, 1.8, 3.6}, {0, 0.1, 0}, {0, 1, 0}, 40};
    view_camera c = view_camera_turntable(&home, 0, 8);
    assert_memory_equal(&c, &home, sizeof(c));
    c = view_camera_turntable(&home, 2, 8); /* a quarter turn */
    assert_vec3_near(c.eye, (view_vec3){3.6, 1.8, 0}, 1e-12);
    assert_vec3_near(c.target, home.target, 0.0);
    c = view_camera_turntable(&home, 4, 8);
    assert_vec3_near(c.eye, (view_vec3){0, 1.8, -3.6}, 1e-12);
}

static void test_view_light_turn_stays_unit_and_keeps_elevation_on_yaw(void **state) {
    (void)state;
    view_camera c = camera_on_z();
    view_vec3 light = {0.6, 0.8, 0};
    view_vec3 turned = view_light_turn(light, &c, 90.0, 0.0);
    assert_vec3_near(turned, (view_vec3){0, 0.8, -0.6}, 1e-12);
    turned = view_light_turn(light, &c, 0.0, 1000.0); /* up to just short of straight above */
    assert_true(fabs(sqrt(turned.x * turned.x + turned.y * turned.y + turned.z * turned.z) - 1.0) <
                1e-12);
    assert_true(turned.y > cos(0.6 * PI / 180.0));
}

static void test_view_bindings_map_keys_to_actions(void **state) {
    (void)state;
    assert_int_equal(view_binding_find('p', false)->action, VIEW_ACTION_SCREENSHOT);
    assert_int_equal(view_binding_find('P', false)->action, VIEW_ACTION_SCREENSHOT);
    assert_int_equal(view_binding_find('w', true)->action, VIEW_ACTION_WRITE_SCENE);
    assert_int_equal(view_binding_find('\t', false)->action, VIEW_ACTION_NEXT_TECHNIQUE);
    assert_int_equal(view_binding_find('\t', true)->action, VIEW_ACTION_PREVIOUS_TECHNIQUE);
    assert_int_equal(view_binding_find('3', false)->action, VIEW_ACTION_SELECT_TECHNIQUE);
    assert_int_equal(view_binding_find('3', false)->argument, 2);
    assert_int_equal(view_binding_find(27, false)->action, VIEW_ACTION_QUIT);
    assert_int_equal(view_binding_find('=', true)->action, VIEW_ACTION_OPTION_UP); /* Shift+= */
    assert_null(view_binding_find('z', false));
    size_t count = 0;
    const view_binding *all = view_bindings(&count);
    for (size_t i = 0; i < count; i++) /* a key listed in the help says what it does */
        assert_true((all[i].keys_text == NULL) == (all[i].help == NULL));
}

static const char *const techniques[] = {"bump", "relief", "vdm", "tessellation"};

static view_state fresh_state(void) {
    view_camera c = camera_on_z();
    view_vec3 light = {0, 1, 0};
    view_state s;
    view_state_init(&s, &c, &light, techniques, 4, 1);
    return s;
}

static void test_view_state_switches_techniques_and_steps_options(void **state) {
    (void)state;
    view_state s = fresh_state();
    assert_string_equal(view_state_technique(&s), "relief");
    assert_true(view_state_main_option(&s) == 16.0);
    assert_true(view_state_apply(&s, VIEW_ACTION_OPTION_UP, 0));
    assert_true(view_state_main_option(&s) == 32.0);
    double most = meso_technique_find_option(meso_technique_find("relief"), "linear_steps")->max;
    for (int i = 0; i < 20; i++) view_state_apply(&s, VIEW_ACTION_OPTION_UP, 0);
    assert_true(view_state_main_option(&s) == most);              /* the option table's limit */
    assert_false(view_state_apply(&s, VIEW_ACTION_OPTION_UP, 0)); /* at its limit */
    assert_true(view_state_apply(&s, VIEW_ACTION_NEXT_TECHNIQUE, 0));
    assert_string_equal(view_state_technique(&s), "vdm");
    assert_true(view_state_apply(&s, VIEW_ACTION_OPTION_DOWN, 0));
    assert_true(view_state_main_option(&s) == 7.0);
    assert_true(view_state_apply(&s, VIEW_ACTION_NEXT_TECHNIQUE, 0));
    assert_true(view_state_apply(&s, VIEW_ACTION_NEXT_TECHNIQUE, 0)); /* wraps */
    assert_string_equal(view_state_technique(&s), "bump");
    assert_true(isnan(view_state_main_option(&s)));
    assert_false(view_state_apply(&s, VIEW_ACTION_TOGGLE_SHADOWS, 0)); /* bump has none */
    assert_false(view_state_apply(&s, VIEW_ACTION_OPTION_UP, 0));
    assert_true(view_state_apply(&s, VIEW_ACTION_PREVIOUS_TECHNIQUE, 0));
    assert_string_equal(view_state_technique(&s), "tessellation");
    assert_true(view_state_apply(&s, VIEW_ACTION_SELECT_TECHNIQUE, 1));
    assert_string_equal(view_state_technique(&s), "relief");
    assert_true(view_state_main_option(&s) == most); /* each technique keeps its own */
    assert_false(view_state_apply(&s, VIEW_ACTION_SELECT_TECHNIQUE, 7)); /* no 8th */
    assert_true(view_state_apply(&s, VIEW_ACTION_TOGGLE_SHADOWS, 0));
    assert_false(s.shadows);
}

static void
test_view_state_display_cycles_only_with_a_reference_and_moving_goes_live(void **state) {
    (void)state;
    view_state s = fresh_state();
    assert_false(view_state_apply(&s, VIEW_ACTION_CYCLE_DISPLAY, 0));
    s.has_reference = true;
    assert_true(view_state_apply(&s, VIEW_ACTION_CYCLE_DISPLAY, 0));
    assert_int_equal(s.display, VIEW_DISPLAY_REFERENCE);
    assert_true(view_state_apply(&s, VIEW_ACTION_CYCLE_DISPLAY, 0));
    assert_int_equal(s.display, VIEW_DISPLAY_DIFFERENCE);
    view_state_drag(&s, VIEW_DRAG_ORBIT, 10, 0, 600);
    assert_int_equal(s.display, VIEW_DISPLAY_LIVE);
    assert_true(s.view_changed);
    assert_true(distance(s.camera.eye, s.home_camera.eye) > 0.1);
    view_state_drag(&s, VIEW_DRAG_LIGHT, 10, 5, 600);
    assert_true(distance(s.light, s.home_light) > 0.01);
    assert_true(view_state_apply(&s, VIEW_ACTION_RESET, 0));
    assert_memory_equal(&s.camera, &s.home_camera, sizeof(s.camera));
    assert_memory_equal(&s.light, &s.home_light, sizeof(s.light));
}

static void test_view_resolution_lowers_when_slow_and_refines_when_still(void **state) {
    (void)state;
    view_resolution r = {1.0, 1.0 / 30.0};
    view_resolution_update(&r, 4.0 / 30.0, true); /* four times too slow: halve a side */
    assert_true(fabs(r.scale - 0.5) < 1e-12);
    view_resolution_update(&r, 100.0, true);
    assert_true(r.scale == VIEW_MIN_SCALE);
    view_resolution_update(&r, 0.1 / 30.0, true); /* fast: up by at most a quarter */
    assert_true(fabs(r.scale - 1.25 * VIEW_MIN_SCALE) < 1e-12);
    view_resolution_update(&r, 0.8 / 30.0, true); /* near the target: kept */
    assert_true(fabs(r.scale - 1.25 * VIEW_MIN_SCALE) < 1e-12);
    view_resolution_update(&r, 0.0, false);
    assert_true(r.scale == 1.0);
    int w, h;
    view_resolution_size(0.5, 800, 600, &w, &h);
    assert_int_equal(w, 400);
    assert_int_equal(h, 300);
    view_resolution_size(0.25, 40, 12, &w, &h);
    assert_int_equal(w, 16);
    assert_int_equal(h, 12);
}

static void test_view_script_parses_every_event(void **state) {
    (void)state;
    view_event e[16];
    char error[256];
    int n = view_script_parse("drag 40,-10; light 1.5,2\n# a comment; key q\n"
                              "pan -3,4 ; wheel -2;key W;key shift+tab; key tab;wait;frames 5;",
                              e, 16, error, sizeof(error));
    assert_int_equal(n, 9);
    assert_int_equal(e[0].type, VIEW_EVENT_DRAG);
    assert_true(e[0].dx == 40 && e[0].dy == -10);
    assert_int_equal(e[1].type, VIEW_EVENT_LIGHT);
    assert_true(e[1].dx == 1.5);
    assert_int_equal(e[2].type, VIEW_EVENT_PAN);
    assert_int_equal(e[3].type, VIEW_EVENT_WHEEL);
    assert_true(e[3].dx == -2);
    assert_int_equal(e[4].key, 'w');
    assert_true(e[4].shift);
    assert_int_equal(e[5].key, '\t');
    assert_true(e[5].shift);
    assert_false(e[6].shift);
    assert_int_equal(e[7].type, VIEW_EVENT_WAIT);
    assert_int_equal(e[8].count, 5);
    assert_int_equal(view_script_parse("", e, 16, error, sizeof(error)), 0);
}

static void test_view_script_errors_name_the_event(void **state) {
    (void)state;
    view_event e[2];
    char error[256];
    assert_int_equal(view_script_parse("key p; drag 1", e, 2, error, sizeof(error)), -1);
    assert_string_equal(error, "event 2: 'drag 1': expected DX,DY");
    assert_int_equal(view_script_parse("jump 3", e, 2, error, sizeof(error)), -1);
    assert_non_null(strstr(error, "event 1: 'jump 3': unknown event"));
    assert_int_equal(view_script_parse("key enter", e, 2, error, sizeof(error)), -1);
    assert_string_equal(error, "event 1: 'key enter': unknown key");
    assert_int_equal(view_script_parse("key a; key b; key c", e, 2, error, sizeof(error)), -1);
    assert_string_equal(error, "more than 2 events");
    assert_int_equal(view_script_parse("frames 0", e, 2, error, sizeof(error)), -1);
}

/* Every switch and main option the viewer steps comes from that technique's option table, and
 * each of the four main options the viewer names is found there (a renamed option would
 * otherwise lose its knob silently). */
static void test_view_knobs_name_real_options_within_range(void **state) {
    (void)state;
    int checked = 0;
    for (size_t t = 0; t < meso_technique_count(); t++) {
        const meso_technique_info *technique = meso_technique_get(t);
        const view_technique_knobs knobs = view_technique_knobs_find(technique->name);
        if (knobs.has_shadows) assert_non_null(meso_technique_find_option(technique, "shadows"));
        if (knobs.has_silhouettes)
            assert_non_null(meso_technique_find_option(technique, "silhouettes"));
        if (!knobs.main_option) continue;
        const meso_technique_option *row = meso_technique_find_option(technique, knobs.main_option);
        if (!row) fail_msg("%s has no option %s", technique->name, knobs.main_option);
        assert_true(row->min <= knobs.main_min && knobs.main_max <= row->max);
        assert_true(knobs.main_default == row->default_value);
        checked++;
    }
    assert_int_equal(checked, 4); /* relief, vdm, tessellation, gdm */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_view_orbit_yaw_turns_about_up_keeping_distance),
        cmocka_unit_test(test_view_knobs_name_real_options_within_range),
        cmocka_unit_test(test_view_orbit_pitch_raises_the_eye_and_stops_before_the_pole),
        cmocka_unit_test(test_view_pan_moves_eye_and_target_by_the_view_height),
        cmocka_unit_test(test_view_zoom_steps_ten_percent_within_limits),
        cmocka_unit_test(test_view_turntable_frame_zero_is_home_and_keeps_height),
        cmocka_unit_test(test_view_light_turn_stays_unit_and_keeps_elevation_on_yaw),
        cmocka_unit_test(test_view_bindings_map_keys_to_actions),
        cmocka_unit_test(test_view_state_switches_techniques_and_steps_options),
        cmocka_unit_test(test_view_state_display_cycles_only_with_a_reference_and_moving_goes_live),
        cmocka_unit_test(test_view_resolution_lowers_when_slow_and_refines_when_still),
        cmocka_unit_test(test_view_script_parses_every_event),
        cmocka_unit_test(test_view_script_errors_name_the_event),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
