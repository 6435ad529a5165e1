/* Placeholder for a module that has no source file yet (CMake needs one). */
typedef int meso_empty_translation_unit;
