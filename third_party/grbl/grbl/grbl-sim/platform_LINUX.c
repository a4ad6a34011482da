/*
  platform_LINUX.c - linux specific functions with generic cross-platform interface

  Part of Grbl Simulator

  Copyright (c) 2014 Adam Shelly

  Grbl is free software: you can redistribute it and/or modify
  it under the terms of the GNU General Public License as published by
  the Free Software Foundation, either version 3 of the License, or
  (at your option) any later version.

  Grbl is distributed in the hope that it will be useful,
  but WITHOUT ANY WARRANTY; without even the implied warranty of
  MERCHANTABILITY or FITNESS FOR A PARTICULAR PURPOSE.  See the
  GNU General Public License for more details.

  You should have received a copy of the GNU General Public License
  along with Grbl.  If not, see <http://www.gnu.org/licenses/>.
*/

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>
#include <termios.h>
#include <time.h>
#include <sys/time.h>
#include <errno.h>
#include <signal.h>
#include <semaphore.h>
#include "platform.h"

#define MS_PER_SEC 1000000


// maobi: the firmware's interrupts run on the simulator's thread, and on an AVR the main
// program stands still while an interrupt runs. The original let both threads run at once,
// so an interrupt could see the planner or the step segment buffer half-written (a stream
// stalled in Run with the position frozen). platform_halt_avr() stops the firmware's thread
// where it is (a signal whose handler waits) for a slice of simulated time, and
// platform_resume_avr() lets it go on, as an interrupt would.
static sem_t avr_halted, avr_resumed;
static pthread_t avr_tid;
static int avr_started = 0;

static void on_halt(int sig) {
  int saved = errno;
  (void)sig;
  sem_post(&avr_halted);
  while (sem_wait(&avr_resumed) != 0) {}
  errno = saved;
}

void platform_halt_avr() {
  if (!avr_started) { return; }
  pthread_kill(avr_tid, SIGUSR1);
  while (sem_wait(&avr_halted) != 0) {}
}

static volatile uint32_t main_checkpoints = 0;

void sim_main_checkpoint(void) {
  __atomic_add_fetch(&main_checkpoints, 1, __ATOMIC_SEQ_CST);
}

uint32_t platform_main_checkpoints() {
  return __atomic_load_n(&main_checkpoints, __ATOMIC_SEQ_CST);
}

void platform_wait_main(uint32_t since, long max_us) {
  long waited = 0;
  if (!avr_started) { return; }
  while (platform_main_checkpoints() == since && waited < max_us) {
    platform_sleep(10);
    waited += 10;
  }
}

void platform_resume_avr() {
  if (!avr_started) { return; }
  sem_post(&avr_resumed);
}

//any platform-specific setup that must be done before sim starts here
void platform_init()
{
  struct sigaction sa = {0};
  sem_init(&avr_halted, 0, 0);
  sem_init(&avr_resumed, 0, 0);
  sa.sa_handler = on_halt;
  sa.sa_flags = SA_RESTART;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGUSR1, &sa, NULL);
}

//cleanup int here;
void platform_terminate()
{
}

//returns a free-running 32 bit nanosecond counter which rolls over
uint32_t platform_ns() 
{
  static uint32_t gTimeBase = 0;
  static uint32_t timestamp;
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC,&ts);
  timestamp = ts.tv_sec*1e9+ts.tv_nsec;
  if (gTimeBase== 0){gTimeBase=timestamp;}
  return timestamp - gTimeBase;;
}

//sleep in microseconds
void platform_sleep(long  microsec)
{
  struct timespec ts={0};
  while (microsec >= MS_PER_SEC){
	 ts.tv_sec++;
	 microsec-=MS_PER_SEC;
  }
  ts.tv_nsec = microsec*1000;
  nanosleep(&ts,NULL);
}

#define SIM_ECHO_TERMINAL 1 //use this to make grbl_sim act like a serial terminal with local echo on.

//set terminal to allow kbhit detection
void enable_kbhit(int dir)
{
  static struct termios oldt, newt;
 
  if ( dir == 1 )
  {
    tcgetattr( STDIN_FILENO, &oldt);
    newt = oldt;
	 newt.c_lflag &= ~( ICANON  ); 
	 if (!SIM_ECHO_TERMINAL) {
		newt.c_lflag &= ~( ECHO );
	 }
    tcsetattr( STDIN_FILENO, TCSANOW, &newt);
  }
  else
    tcsetattr( STDIN_FILENO, TCSANOW, &oldt);
}
 
//detect key pressed
int kbhit (void)
{
  struct timeval tv={0};
  fd_set rdfs={{0}};
  int retval;

  /* tv.tv_sec = 0; */
  /* tv.tv_usec = 0; */
 
  /* FD_ZERO(&rdfs); */
  FD_SET (STDIN_FILENO, &rdfs);
 
  select(STDIN_FILENO+1, &rdfs, NULL, NULL, &tv);
  retval = FD_ISSET(STDIN_FILENO, &rdfs);

  return retval;
}

plat_thread_t* platform_start_thread(plat_threadfunc_t threadfunc) {
  plat_thread_t* th = malloc(sizeof(plat_thread_t));
  if (pthread_create(&th->tid, NULL, threadfunc, &th->exit)){
	 free(th);
	 return NULL;
  }
  avr_tid = th->tid;
  avr_started = 1;
  return th;
}

//ask thread to exit nicely, wait
void platform_stop_thread(plat_thread_t* th){
  th->exit = 1;
  pthread_join(th->tid,NULL);  
}

//force-kill thread
void platform_kill_thread(plat_thread_t* th){
  th->exit = 1;
  pthread_cancel(th->tid); 
}

//return char if one available.
// maobi: read(2) one byte straight from the descriptor. The original read through stdio
// (getchar), whose buffer kept the rest of a line out of kbhit()'s select(), so a line
// written in one piece stalled until more bytes came; and it switched the terminal's
// modes around every poll, racing whoever else configures the pseudo-terminal.
uint8_t platform_poll_stdin() {
  uint8_t char_in=0;
  if (kbhit()) {
	 if (read(STDIN_FILENO, &char_in, 1) != 1) {
		char_in = 0x06; // end of input or a read error: exit like ^F (EOF is 0xFF as uint8_t)
	 }
  }
  return char_in;
}
