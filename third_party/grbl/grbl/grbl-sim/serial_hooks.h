#define serial_read orig_serial_read

