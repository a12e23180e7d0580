#include "viewer_page.hpp"

#include <stdexcept>

#if defined(UMBRA_HAVE_VIEWER)
#include "umbra_viewer_assets.hpp"
#endif

namespace umbra::cli {

#if defined(UMBRA_HAVE_VIEWER)

bool viewer_page_available() { return true; }

std::string viewer_three_version() { return std::string(viewer_assets::kThreeVersion); }

std::string viewer_page(const OccupancyMap& map, const ViewerData& data, const std::string& title) {
  std::string page(viewer_assets::kPageBeforeData);
  page += "<script type=\"application/json\" id=\"umbra-map\">" + viewer_json(map, data, title) + "</script>\n";
  std::size_t id = 0;
  for (const ViewerLayer& layer : data.layers) {
    if (!layer.embedded) continue;
    page += "<script type=\"application/octet-stream\" id=\"layer-" + std::to_string(id++) + "\">";
    page += base64(layer.deflated);
    page += "</script>\n";
  }
  page += "<script>";
  page += viewer_assets::kScript;
  page += "</script>";
  page += viewer_assets::kPageAfterData;
  return page;
}

#else

bool viewer_page_available() { return false; }

std::string viewer_three_version() { return {}; }

std::string viewer_page(const OccupancyMap&, const ViewerData&, const std::string&) {
  throw std::logic_error("umbra was built without the page of `umbra view` (node and npm were missing)");
}

#endif

}  // namespace umbra::cli
