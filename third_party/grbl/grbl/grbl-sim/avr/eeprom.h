
#include "../eeprom.h"
void eeprom_close();
