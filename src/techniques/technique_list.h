/* Every technique, in the order `meso render --techniques all` and the demo show them.
 * Each line names a `const meso_technique meso_technique_<name>` defined in <name>.c here.
 * Add a technique: write techniques/<name>.c and add its line. */
MESO_TECHNIQUE(flat)
MESO_TECHNIQUE(bump)
MESO_TECHNIQUE(horizon)
MESO_TECHNIQUE(parallax)
MESO_TECHNIQUE(relief)
MESO_TECHNIQUE(relief_exact)
MESO_TECHNIQUE(relief_layers)
MESO_TECHNIQUE(vdm)
MESO_TECHNIQUE(gdm)
MESO_TECHNIQUE(tessellation)
MESO_TECHNIQUE(displacement)
