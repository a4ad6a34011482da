#define main avr_main
