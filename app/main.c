/* Placeholder: the meso program (app helper replaces this). */
#include <stdio.h>
int main(void) { fputs("meso: not built yet\n", stderr); return 1; }
