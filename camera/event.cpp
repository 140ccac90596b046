#include "camera/event.h"
