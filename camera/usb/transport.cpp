#include "camera/usb/transport.h"

namespace yelan::camera::usb {

const char* model_name(Model m) { return m == Model::davis346 ? "DAVIS346" : "DVXplorer"; }

}  // namespace yelan::camera::usb
