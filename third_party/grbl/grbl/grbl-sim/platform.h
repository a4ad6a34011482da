#ifndef platform_h

#ifdef  PLAT_LINUX
#include "platform_linux.h"
#elif  PLAT_OSX
#include "platform_osx.h"
#else
#include "platform_windows.h"
#endif

#define platform_h
#include <inttypes.h>

void platform_init();
void platform_terminate();

plat_thread_t* platform_start_thread(plat_threadfunc_t func);
void platform_stop_thread(plat_thread_t* thread);
void platform_kill_thread(plat_thread_t* thread);

uint32_t  platform_ns();  //monotonically increasing nanoseconds since program start.
void platform_sleep(long microsec); //sleep for suggested time in microsec.

uint8_t platform_poll_stdin();
// maobi: stop the firmware's thread while simulated interrupts run (Linux only).
void platform_halt_avr();
void platform_resume_avr();
// maobi: the firmware's main program passed a point where it waits (serial_read, st_prep_buffer).
void sim_main_checkpoint(void);
// maobi: wait, at most max_us, until the main program has passed such a point since `since`.
void platform_wait_main(uint32_t since, long max_us);
uint32_t platform_main_checkpoints(); //non-blocking stdin read - returns 0 if no char present, 0xFF for EOF

#endif
