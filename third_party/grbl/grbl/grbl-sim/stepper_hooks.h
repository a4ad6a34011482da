/*
  stepper_hooks.h - maobi: lets the simulator know that the firmware's main program has
  refilled the step segment buffer (see sim_main_checkpoint in platform_LINUX.c).

  Part of the Grbl Simulator as vendored by maobi (third_party/grbl/README.md).

  Grbl is free software: you can redistribute it and/or modify
  it under the terms of the GNU General Public License as published by
  the Free Software Foundation, either version 3 of the License, or
  (at your option) any later version.
*/

void orig_st_prep_buffer();
// The validator has no simulator thread: this default does nothing.
void __attribute__((weak)) sim_main_checkpoint(void) {}
void st_prep_buffer() {
  orig_st_prep_buffer();
  sim_main_checkpoint();
}
#define st_prep_buffer orig_st_prep_buffer
