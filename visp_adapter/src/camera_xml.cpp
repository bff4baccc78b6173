// ViSP camera XML through vpXmlParserCamera (values) and libxml2 (the file's structure); see
// camera_xml.hpp.
#include "visp_adapter/camera_xml.hpp"
#include "visp_camera.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>

#include <libxml/parser.h>
#include <libxml/tree.h>
#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpXmlParserCamera.h>

namespace pepper::visp_adapter {
namespace {

vpCameraParameters::vpCameraParametersProjType to_visp(CameraModel model) {
  return model == CameraModel::kPerspectiveWithDistortion
             ? vpCameraParameters::perspectiveProjWithDistortion
             : vpCameraParameters::perspectiveProjWithoutDistortion;
}

// ViSP announces every camera it meets on std::cout; silence it for one call (camera_xml.hpp).
template <class F>
auto with_quiet_cout(F&& f) {
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  std::ostringstream sink;
  std::streambuf* const saved = std::cout.rdbuf(sink.rdbuf());
  struct Restore {
    std::streambuf* saved;
    ~Restore() { std::cout.rdbuf(saved); }
  } restore{saved};
  return f();
}

std::string text_of(xmlNode* node) {
  xmlChar* content = xmlNodeGetContent(node);
  std::string text = content ? reinterpret_cast<const char*>(content) : "";
  xmlFree(content);
  const auto b = text.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  return text.substr(b, text.find_last_not_of(" \t\r\n") - b + 1);
}

bool is(xmlNode* node, const char* name) {
  return node->type == XML_ELEMENT_NODE && xmlStrEqual(node->name, reinterpret_cast<const xmlChar*>(name));
}

int size_of(const std::string& path, xmlNode* node) {
  const std::string text = text_of(node);
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size() || value < 0) {
    throw CameraXmlError(path, "line " + std::to_string(node->line) + ": <" +
                                   reinterpret_cast<const char*>(node->name) +
                                   "> is not an image size: '" + text + "'");
  }
  return static_cast<int>(value);
}

void require_number(const std::string& path, xmlNode* node) {
  const std::string text = text_of(node);
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(value)) {
    throw CameraXmlError(path, "line " + std::to_string(node->line) + ": <" +
                                   reinterpret_cast<const char*>(node->name) +
                                   "> is not a number: '" + text + "'");
  }
}

std::string describe(const std::vector<CameraEntry>& entries) {
  std::ostringstream os;
  for (size_t i = 0; i < entries.size(); ++i) {
    const CameraEntry& e = entries[i];
    os << (i ? "; " : "") << "'" << e.name << "' " << e.width_px << "x" << e.height_px << " (";
    for (size_t m = 0; m < e.models.size(); ++m) os << (m ? ", " : "") << to_string(e.models[m]);
    os << ")";
  }
  return os.str();
}

std::string describe_request(const std::string& name, CameraModel model, int width_px, int height_px) {
  std::ostringstream os;
  os << "camera '" << name << "'";
  if (width_px > 0 || height_px > 0) os << " of image size " << width_px << "x" << height_px;
  os << " with model " << to_string(model);
  return os.str();
}

}  // namespace

const char* to_string(CameraModel model) {
  return model == CameraModel::kPerspectiveWithDistortion ? "perspectiveProjWithDistortion"
                                                          : "perspectiveProjWithoutDistortion";
}

CameraXmlError::CameraXmlError(const std::string& path, const std::string& cause)
    : std::runtime_error(path + ": " + cause), path_(path), cause_(cause) {}

std::vector<CameraEntry> list_camera_xml(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw CameraXmlError(path, "no such file");
  if (!std::ifstream(path)) throw CameraXmlError(path, "cannot open for reading");
  // libxml2 reports every error through this callback (thread-local in libxml2); the first one
  // is where the file goes wrong, the last one is often only "premature end of data".
  struct FirstError {
    bool set = false;
    int line = 0;
    std::string message;
  } first;
  xmlSetStructuredErrorFunc(&first, [](void* user, xmlErrorPtr err) {
    auto* f = static_cast<FirstError*>(user);
    if (f->set || !err) return;
    f->set = true;
    f->line = err->line;
    f->message = err->message ? err->message : "";
    while (!f->message.empty() && (f->message.back() == '\n' || f->message.back() == ' ')) {
      f->message.pop_back();
    }
  });
  xmlDoc* doc = xmlReadFile(path.c_str(), nullptr, XML_PARSE_NONET | XML_PARSE_NOWARNING);
  xmlSetStructuredErrorFunc(nullptr, nullptr);
  if (!doc) {
    std::string cause = "not a well-formed XML file";
    if (first.set) cause += " (line " + std::to_string(first.line) + ": " + first.message + ")";
    throw CameraXmlError(path, cause);
  }
  const std::unique_ptr<xmlDoc, void (*)(xmlDoc*)> owned(doc, xmlFreeDoc);
  xmlNode* root = xmlDocGetRootElement(doc);
  if (!root || !is(root, "root")) {
    throw CameraXmlError(path, "the document element is not <root> (not a ViSP camera XML file)");
  }
  std::vector<CameraEntry> entries;
  for (xmlNode* cam = root->children; cam; cam = cam->next) {
    if (!is(cam, "camera")) continue;
    CameraEntry e;
    for (xmlNode* f = cam->children; f; f = f->next) {
      if (is(f, "name")) e.name = text_of(f);
      else if (is(f, "image_width")) e.width_px = size_of(path, f);
      else if (is(f, "image_height")) e.height_px = size_of(path, f);
      else if (is(f, "model")) {
        for (xmlNode* t = f->children; t; t = t->next) {
          // ViSP reads a parameter that is not a number as 0 without a word: refuse it here.
          for (const char* param : {"px", "py", "u0", "v0", "kud", "kdu"})
            if (is(t, param)) require_number(path, t);
          if (!is(t, "type")) continue;
          const std::string type = text_of(t);
          for (const CameraModel m : {CameraModel::kPerspectiveWithoutDistortion, CameraModel::kPerspectiveWithDistortion})
            if (type == to_string(m)) e.models.push_back(m);
        }
      }
    }
    entries.push_back(std::move(e));
  }
  if (entries.empty()) throw CameraXmlError(path, "no <camera> in <root> (not a ViSP camera XML file?)");
  return entries;
}

CameraCalibration read_camera_xml(const std::string& path, const std::string& name, CameraModel model,
                                  int width_px, int height_px) {
  const std::vector<CameraEntry> entries = list_camera_xml(path);  // missing/malformed: named there
  if (width_px < 0 || height_px < 0) throw CameraXmlError(path, "requested image size must be >= 0");
  vpCameraParameters cam;
  vpXmlParserCamera parser;
  const int rc = with_quiet_cout([&] {
    return parser.parse(cam, path, name, to_visp(model), static_cast<unsigned>(width_px),
                        static_cast<unsigned>(height_px));
  });
  if (rc != vpXmlParserCamera::SEQUENCE_OK) {
    throw CameraXmlError(path, "ViSP's vpXmlParserCamera finds no " +
                                   describe_request(name, model, width_px, height_px) +
                                   "; the file holds " + describe(entries));
  }
  CameraCalibration c;
  c.name = name;
  c.width_px = static_cast<int>(parser.getWidth());
  c.height_px = static_cast<int>(parser.getHeight());
  c.model = model;
  c.px = cam.get_px();
  c.py = cam.get_py();
  c.u0 = cam.get_u0();
  c.v0 = cam.get_v0();
  if (model == CameraModel::kPerspectiveWithDistortion) {
    c.kud = cam.get_kud();
    c.kdu = cam.get_kdu();
  }
  return c;
}

void write_camera_xml(const std::string& path, const CameraCalibration& c) {
  for (const double v : {c.px, c.py, c.u0, c.v0, c.kud, c.kdu}) {
    if (!std::isfinite(v)) throw CameraXmlError(path, "refusing to write a non-finite parameter");
  }
  if (c.width_px < 0 || c.height_px < 0) throw CameraXmlError(path, "image size must be >= 0");
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    for (const CameraEntry& e : list_camera_xml(path)) {
      if (e.name != c.name || e.width_px != c.width_px || e.height_px != c.height_px) continue;
      for (const CameraModel m : e.models)
        if (m == c.model) {
          throw CameraXmlError(path, "already holds " + describe_request(c.name, c.model, c.width_px, c.height_px) +
                                         " (ViSP does not overwrite a camera model)");
        }
    }
  }
  const vpCameraParameters cam = to_visp_camera(c);
  vpXmlParserCamera parser;
  const int rc = with_quiet_cout([&] {
    return parser.save(cam, path, c.name, static_cast<unsigned>(c.width_px), static_cast<unsigned>(c.height_px));
  });
  if (rc != vpXmlParserCamera::SEQUENCE_OK) {
    throw CameraXmlError(path, "ViSP's vpXmlParserCamera could not write " +
                                   describe_request(c.name, c.model, c.width_px, c.height_px));
  }
}

}  // namespace pepper::visp_adapter
