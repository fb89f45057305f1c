#include "transport/fastdds/intraprocess_builtin.hpp"

#include <fastrtps/attributes/LibrarySettingsAttributes.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <mutex>

namespace tessera::transport {

void keep_builtin_traffic_off_intraprocess() {
  // Serialised: participants are created from several threads of one process (tests, the
  // online agent's stream and channel).
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  // Loading the profiles after setting the library's attributes would reset them to the XML
  // file's (or the defaults), so load first; Fast DDS loads them only once.
  eprosima::fastdds::dds::DomainParticipantFactory::get_instance()->load_profiles();
  namespace xml = eprosima::fastrtps::xmlparser;
  eprosima::fastrtps::LibrarySettingsAttributes library =
      xml::XMLProfileManager::library_settings();
  if (library.intraprocess_delivery != eprosima::fastrtps::INTRAPROCESS_FULL) return;
  library.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_USER_DATA_ONLY;
  xml::XMLProfileManager::library_settings(library);
}

}  // namespace tessera::transport
