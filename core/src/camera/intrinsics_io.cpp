// Intrinsics files: ViSP camera XML and the plain YAML/JSON form (see intrinsics_io.hpp).
#include "core/camera/intrinsics_io.hpp"
#include "core/camera/intrinsics_json.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <cstdlib>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

namespace pepper::core::camera {
namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void require_readable(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw IntrinsicsFileError(path, "no such file");
  }
  std::ifstream in(path);
  if (!in) throw IntrinsicsFileError(path, "cannot open for reading");
}

void require_valid(const std::string& path, const CameraIntrinsics& k) {
  const auto errors = k.validate();
  if (errors.empty()) return;
  std::string msg = "invalid intrinsics:";
  for (const auto& e : errors) msg += " " + e + ";";
  throw IntrinsicsFileError(path, msg);
}


// Minimal XML reader for ViSP's camera files: elements, text, comments, declarations; attributes
// are skipped. ViSP 3.5's own headers (vpXmlParserCamera) do not compile as C++20 under GCC 12
// (vpArray2D's `vpArray2D<Type>()` constructor declarations, DR 2237), so we read the
// format ourselves; the format is ViSP's (see intrinsics_io.hpp).
struct XmlNode {
  std::string name;
  std::string text;
  std::vector<XmlNode> children;
  const XmlNode* child(const std::string& n) const {
    for (const auto& c : children)
      if (c.name == n) return &c;
    return nullptr;
  }
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

XmlNode parse_xml(const std::string& doc) {
  XmlNode root;
  root.name = "#document";
  std::vector<XmlNode*> stack{&root};
  size_t i = 0;
  while (i < doc.size()) {
    if (doc[i] != '<') {
      const size_t lt = doc.find('<', i);
      const size_t stop = lt == std::string::npos ? doc.size() : lt;
      stack.back()->text += doc.substr(i, stop - i);
      i = stop;
      continue;
    }
    if (doc.compare(i, 4, "<!--") == 0) {
      const size_t e = doc.find("-->", i + 4);
      if (e == std::string::npos) throw std::runtime_error("unterminated comment");
      i = e + 3;
      continue;
    }
    if (doc.compare(i, 2, "<?") == 0 || doc.compare(i, 2, "<!") == 0) {
      const size_t e = doc.find('>', i);
      if (e == std::string::npos) throw std::runtime_error("unterminated declaration");
      i = e + 1;
      continue;
    }
    const size_t gt = doc.find('>', i);
    if (gt == std::string::npos) throw std::runtime_error("unterminated tag");
    std::string tag = doc.substr(i + 1, gt - i - 1);
    i = gt + 1;
    if (!tag.empty() && tag[0] == '/') {
      const std::string name = trim(tag.substr(1));
      if (stack.size() < 2 || stack.back()->name != name) {
        throw std::runtime_error("unexpected closing tag </" + name + ">");
      }
      stack.pop_back();
      continue;
    }
    const bool self_closing = !tag.empty() && tag.back() == '/';
    if (self_closing) tag.pop_back();
    const size_t sp = tag.find_first_of(" \t\r\n");
    XmlNode node;
    node.name = trim(tag.substr(0, sp));
    if (node.name.empty()) throw std::runtime_error("empty tag name");
    stack.back()->children.push_back(std::move(node));
    if (!self_closing) stack.push_back(&stack.back()->children.back());
  }
  if (stack.size() != 1) throw std::runtime_error("unclosed element <" + stack.back()->name + ">");
  return root;
}

void collect(const XmlNode& n, const std::string& name, std::vector<const XmlNode*>& out) {
  for (const auto& c : n.children) {
    if (c.name == name) out.push_back(&c);
    else collect(c, name, out);
  }
}

double parse_number(const std::string& path, const std::string& what, const std::string& text) {
  const std::string t = trim(text);
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (t.empty() || end != t.c_str() + t.size()) {
    throw IntrinsicsFileError(path, "<" + what + "> is not a number: '" + t + "'");
  }
  return v;
}

double number(const std::string& path, const XmlNode& parent, const std::string& name) {
  const XmlNode* n = parent.child(name);
  if (!n) throw IntrinsicsFileError(path, "missing <" + name + "> in <" + parent.name + ">");
  return parse_number(path, name, n->text);
}

double number_or(const std::string& path, const XmlNode* n, double fallback) {
  return n ? parse_number(path, n->name, n->text) : fallback;
}

}  // namespace

IntrinsicsFileError::IntrinsicsFileError(const std::string& path, const std::string& cause)
    : std::runtime_error(path + ": " + cause), path_(path) {}

CameraIntrinsics load_visp_camera_xml(const std::string& path, const std::string& camera_name,
                                      int width_px, int height_px) {
  require_readable(path);
  if (width_px < 0 || height_px < 0) {
    throw IntrinsicsFileError(path, "requested image size must be >= 0");
  }
  std::ifstream in(path, std::ios::binary);
  std::ostringstream buf;
  buf << in.rdbuf();
  XmlNode root;
  try {
    root = parse_xml(buf.str());
  } catch (const std::runtime_error& e) {
    throw IntrinsicsFileError(path, std::string("not a well-formed XML file: ") + e.what());
  }
  // ViSP files: <root><camera>...</camera>...</root>; accept <camera> at any depth.
  std::vector<const XmlNode*> cameras;
  collect(root, "camera", cameras);
  if (cameras.empty()) throw IntrinsicsFileError(path, "no <camera> element (not a ViSP camera XML?)");
  bool saw_name = false;
  for (const XmlNode* cam : cameras) {
    const XmlNode* name = cam->child("name");
    const std::string cam_name = name ? trim(name->text) : std::string();
    if (!camera_name.empty() && cam_name != camera_name) continue;
    saw_name = true;
    const int w = static_cast<int>(number_or(path, cam->child("image_width"), 0.0));
    const int h = static_cast<int>(number_or(path, cam->child("image_height"), 0.0));
    if (width_px > 0 && height_px > 0 && (w != width_px || h != height_px)) continue;
    for (const XmlNode& model : cam->children) {
      if (model.name != "model") continue;
      const XmlNode* type = model.child("type");
      if (!type || trim(type->text) != "perspectiveProjWithoutDistortion") continue;
      CameraIntrinsics k;
      k.width_px = width_px > 0 ? width_px : w;
      k.height_px = height_px > 0 ? height_px : h;
      k.fx_px = number(path, model, "px");
      k.fy_px = number(path, model, "py");
      k.cx_px = number(path, model, "u0");
      k.cy_px = number(path, model, "v0");
      if (k.width_px <= 0 || k.height_px <= 0) {
        throw IntrinsicsFileError(path, "camera '" + cam_name +
                                            "' has no <image_width>/<image_height> and none was requested");
      }
      require_valid(path, k);
      return k;
    }
  }
  std::ostringstream os;
  if (!saw_name) {
    os << "no camera named '" << camera_name << "'";
  } else {
    os << "no camera";
    if (!camera_name.empty()) os << " '" << camera_name << "'";
    if (width_px > 0) os << " with image size " << width_px << "x" << height_px;
    os << " has a <model> of type perspectiveProjWithoutDistortion";
  }
  throw IntrinsicsFileError(path, os.str());
}

CameraIntrinsics load_intrinsics_plain(const std::string& path) {
  require_readable(path);
  const std::string ext = lower_extension(path);
  CameraIntrinsics k;
  if (ext == ".json") {
    std::ifstream in(path);
    nlohmann::json j;
    try {
      in >> j;
    } catch (const std::exception& e) {
      throw IntrinsicsFileError(path, std::string("not valid JSON: ") + e.what());
    }
    try {
      k = intrinsics_from_json(j);
    } catch (const std::invalid_argument& e) {
      throw IntrinsicsFileError(path, e.what());
    }
  } else if (ext == ".yaml" || ext == ".yml") {
    YAML::Node root;
    try {
      root = YAML::LoadFile(path);
    } catch (const std::exception& e) {
      throw IntrinsicsFileError(path, std::string("not valid YAML: ") + e.what());
    }
    auto get = [&](const char* key) -> double {
      if (!root.IsMap() || !root[key]) {
        throw IntrinsicsFileError(path, std::string("missing key '") + key + "'");
      }
      try {
        return root[key].as<double>();
      } catch (const std::exception&) {
        throw IntrinsicsFileError(path, std::string("non-numeric key '") + key + "'");
      }
    };
    k = intrinsics_from_keys(get);
  } else {
    throw IntrinsicsFileError(path, "unknown extension '" + ext + "' (expected .yaml, .yml, .json)");
  }
  require_valid(path, k);
  return k;
}

CameraIntrinsics load_intrinsics(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".xml") return load_visp_camera_xml(path);
  return load_intrinsics_plain(path);
}

void save_intrinsics_plain(const CameraIntrinsics& k, const std::string& path) {
  const std::string ext = lower_extension(path);
  std::ostringstream os;
  os.precision(17);
  if (ext == ".yaml" || ext == ".yml") {
    os << "width_px: " << k.width_px << "\nheight_px: " << k.height_px << "\nfx_px: " << k.fx_px
       << "\nfy_px: " << k.fy_px << "\ncx_px: " << k.cx_px << "\ncy_px: " << k.cy_px << "\n";
  } else {
    os << intrinsics_to_json(k).dump(2) << "\n";
  }
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw IntrinsicsFileError(path, "cannot open for writing");
    out << os.str();
    if (!out) throw IntrinsicsFileError(path, "write failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw IntrinsicsFileError(path, "rename failed: " + ec.message());
}

}  // namespace pepper::core::camera
