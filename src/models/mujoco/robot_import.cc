#include "models/mujoco/robot_import.h"

#include <tinyxml2.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "common/units.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;
using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;

std::string g6(double v) {
  char b[48];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// A name from the user's file or experiment as a message shows it: control characters as \xHH, at
// most 60 characters (then "...").
std::string clipped(const std::string& v) {
  std::string out;
  for (const char ch : v) {
    if (out.size() >= 60) return out + "...";
    const unsigned char u = static_cast<unsigned char>(ch);
    if (u < 0x20 || u == 0x7f) {
      char b[8];
      std::snprintf(b, sizeof b, "\\x%02x", u);
      out += b;
    } else {
      out += ch;
    }
  }
  return out;
}

[[noreturn]] void fail(const std::string& file, const std::string& what, const std::string& key = "robot.mjcf") {
  throw RobotImportError(file + ": " + what, key);
}

void loadXmlFile(XMLDocument& doc, const std::string& file) {
  if (doc.LoadFile(file.c_str()) != tinyxml2::XML_SUCCESS)
    fail(file, std::string("cannot read it as XML: ") + (doc.ErrorStr() ? doc.ErrorStr() : "unknown error"));
}

// Every element below `e` (depth first, document order), `e` itself excluded.
void forEachElement(XMLElement* e, const std::function<void(XMLElement*)>& f) {
  for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
    f(c);
    forEachElement(c, f);
  }
}

// <include file="..."/> replaced by the children of the included file's <mujoco> (recursively, each
// file relative to the file that names it), as MuJoCo's own parser does.
void inlineIncludes(XMLDocument& doc, XMLElement* root, const fs::path& dir, int depth) {
  if (depth > 8) fail(dir.string(), "includes nested more than 8 deep");
  std::vector<XMLElement*> includes;
  forEachElement(root, [&](XMLElement* e) {
    if (std::string(e->Name()) == "include") includes.push_back(e);
  });
  for (XMLElement* inc : includes) {
    const char* f = inc->Attribute("file");
    if (!f) fail(dir.string(), "an <include> without file=");
    const fs::path p = fs::path(f).is_absolute() ? fs::path(f) : dir / f;
    XMLDocument sub;
    loadXmlFile(sub, p.string());
    XMLElement* subRoot = sub.RootElement();
    if (!subRoot || std::string(subRoot->Name()) != "mujoco") fail(p.string(), "an included file must be <mujoco>");
    inlineIncludes(sub, subRoot, p.parent_path(), depth + 1);
    tinyxml2::XMLNode* parent = inc->Parent();
    tinyxml2::XMLNode* after = inc;
    for (XMLElement* c = subRoot->FirstChildElement(); c; c = c->NextSiblingElement()) {
      tinyxml2::XMLNode* copy = c->DeepClone(&doc);
      parent->InsertAfterChild(after, copy);
      after = copy;
    }
    parent->DeleteChild(inc);
  }
}

// The default classes of an MJCF model and the attribute a geom gets from them (MuJoCo's rules:
// the geom's class, else the nearest enclosing body's childclass, else "main"; a class inherits
// from the classes that enclose it).
class Defaults {
 public:
  explicit Defaults(XMLElement* root) {
    for (XMLElement* d = root->FirstChildElement("default"); d; d = d->NextSiblingElement("default")) add(d, true);
  }
  const char* geomAttr(XMLElement* geom, const char* name) const {
    if (const char* v = geom->Attribute(name)) return v;
    std::string cls = "main";
    if (const char* c = geom->Attribute("class")) {
      cls = c;
    } else {
      for (tinyxml2::XMLNode* p = geom->Parent(); p; p = p->Parent()) {
        XMLElement* b = p->ToElement();
        if (b && std::string(b->Name()) == "body" && b->Attribute("childclass")) {
          cls = b->Attribute("childclass");
          break;
        }
      }
    }
    const auto it = classes_.find(cls);
    for (XMLElement* d = it == classes_.end() ? nullptr : it->second; d;) {
      if (XMLElement* gd = d->FirstChildElement("geom"))
        if (const char* v = gd->Attribute(name)) return v;
      XMLElement* up = d->Parent() ? d->Parent()->ToElement() : nullptr;
      d = up && std::string(up->Name()) == "default" ? up : nullptr;
    }
    return nullptr;
  }

 private:
  void add(XMLElement* d, bool top) {
    const char* c = d->Attribute("class");
    classes_[c ? c : (top ? "main" : "")] = d;
    for (XMLElement* k = d->FirstChildElement("default"); k; k = k->NextSiblingElement("default")) add(k, false);
  }
  std::map<std::string, XMLElement*> classes_;
};

std::string stemOf(const std::string& file) { return fs::path(file).stem().string(); }

bool isFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

// A temporary file named like /tmp/tailsim-<what>-XXXXXX<suffix>, removed with the object.
class TempFile {
 public:
  TempFile(const std::string& what, const std::string& suffix, const std::string& for_file) {
    std::string t = "/tmp/tailsim-" + what + "-XXXXXX" + suffix;
    std::vector<char> buf(t.begin(), t.end());
    buf.push_back('\0');
    const int fd = mkstemps(buf.data(), static_cast<int>(suffix.size()));
    if (fd < 0) fail(for_file, "cannot create a temporary file in /tmp");
    ::close(fd);
    path_ = buf.data();
  }
  ~TempFile() { std::remove(path_.c_str()); }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// URDF: MuJoCo reads it and writes it back as MJCF; the returned text then goes through the MJCF
// steps. MuJoCo's URDF reader fuses bodies without joints into their parents (compiler fusestatic),
// the root link into the world: the URDF is given MuJoCo's extension element
// <mujoco><compiler fusestatic="false"/></mujoco> so that the root link stays a body, and that body
// gets the free joint a standing robot needs (unless the URDF gives it one, a floating joint from a
// link with nothing else). Visual elements are discarded (the reader's default); mesh and texture
// folders are made absolute, the text being read from /tmp.
// A URDF's collision meshes are files MuJoCo's reader looks for in meshdir by their file name (it
// strips the path, package:// included); one that is missing is the same error as an MJCF's
// colliding geom without its mesh, naming the link and the file, before MuJoCo reads the URDF.
void missingUrdfCollisionMeshes(const XMLElement* robot, const char* meshdir, const std::string& file) {
  std::vector<std::string> missing;
  for (const XMLElement* link = robot->FirstChildElement("link"); link; link = link->NextSiblingElement("link"))
    for (const XMLElement* c = link->FirstChildElement("collision"); c; c = c->NextSiblingElement("collision")) {
      const XMLElement* g = c->FirstChildElement("geometry");
      const XMLElement* mesh = g ? g->FirstChildElement("mesh") : nullptr;
      const char* f = mesh ? mesh->Attribute("filename") : nullptr;
      if (!f) continue;
      const fs::path p = fs::path(meshdir ? meshdir : "") / fs::path(f).filename();
      if (!isFile(p))
        missing.push_back("a collision of link '" + clipped(link->Attribute("name") ? link->Attribute("name") : "?") +
                          "': its mesh " + clipped(f) + " is missing (looked for " + p.string() + ")");
    }
  if (missing.empty()) return;
  std::string msg = std::to_string(missing.size()) + " colliding geom" + (missing.size() > 1 ? "s have" : " has") +
                    " a missing mesh file: ";
  for (std::size_t i = 0; i < missing.size() && i < 5; ++i) msg += (i ? "; " : "") + missing[i];
  if (missing.size() > 5) msg += "; and " + std::to_string(missing.size() - 5) + " more";
  fail(file, msg + ". Supply the mesh files (meshdir " + std::string(meshdir ? meshdir : "") +
                 "), or remove those <collision> elements");
}

std::string urdfToMjcf(const std::string& file, std::map<std::string, double>& efforts) {
  XMLDocument urdf;
  loadXmlFile(urdf, file);
  XMLElement* robot = urdf.RootElement();
  XMLElement* ext = robot->FirstChildElement("mujoco");
  if (!ext) {
    ext = urdf.NewElement("mujoco");
    robot->InsertFirstChild(ext);
  }
  XMLElement* compiler = ext->FirstChildElement("compiler");
  if (!compiler) {
    compiler = urdf.NewElement("compiler");
    ext->InsertFirstChild(compiler);
  }
  compiler->SetAttribute("fusestatic", "false");
  // A link without <inertial> weighs nothing in URDF; MuJoCo's default (inertiafromgeom "auto")
  // would give it its collision geoms' mass at density 1000. The URDF's own setting wins.
  const bool massless_links = !compiler->Attribute("inertiafromgeom");
  if (massless_links) compiler->SetAttribute("inertiafromgeom", "false");
  const std::string inertia_from_geom = compiler->Attribute("inertiafromgeom");
  const fs::path dir = fs::path(file).parent_path();
  for (const char* attr : {"meshdir", "texturedir"}) {
    const char* v = compiler->Attribute(attr);
    const fs::path p = v ? fs::path(v) : fs::path();
    std::string a = (p.is_absolute() ? p : (dir / p).lexically_normal()).string();
    if (a.empty() || a.back() != '/') a += "/";
    compiler->SetAttribute(attr, a.c_str());
  }
  missingUrdfCollisionMeshes(robot, compiler->Attribute("meshdir"), file);
  for (XMLElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const XMLElement* limit = j->FirstChildElement("limit");
    const char* name = j->Attribute("name");
    if (name && limit && limit->DoubleAttribute("effort", 0.0) > 0.0) efforts[name] = limit->DoubleAttribute("effort");
  }
  TempFile in("urdf", ".urdf", file);
  if (urdf.SaveFile(in.path().c_str()) != tinyxml2::XML_SUCCESS) fail(file, "cannot write a temporary copy of the URDF");

  installMujocoMessageHandlers();
  char err[1000] = "";
  ModelPtr m(mj_loadXML(in.path().c_str(), nullptr, err, sizeof err));
  if (!m) {
    std::string why = std::string("MuJoCo cannot load this URDF: ") + err;
    if (why.find("Unknown mesh file type") != std::string::npos)
      why += " (MuJoCo 2.2 reads STL, OBJ and MSH meshes: convert that mesh, or let the visual elements be discarded "
             "(no discardvisual=\"false\"))";
    if (massless_links && why.find("mass and inertia") != std::string::npos)
      why += " (a link without <inertial> has no mass in URDF, and tailsim reads it so: give the moving links "
             "an <inertial>, or add <mujoco><compiler inertiafromgeom=\"auto\"/></mujoco> to take their mass "
             "from their collision geoms)";
    fail(file, why);
  }
  TempFile out("urdf", ".xml", file);
  const bool ok = mj_saveLastXML(out.path().c_str(), m.get(), err, sizeof err);
  if (!ok) fail(file, std::string("MuJoCo cannot write this URDF as MJCF: ") + err);
  XMLDocument mjcf;
  loadXmlFile(mjcf, out.path());
  XMLElement* world = mjcf.RootElement() ? mjcf.RootElement()->FirstChildElement("worldbody") : nullptr;
  XMLElement* base = world ? world->FirstChildElement("body") : nullptr;
  if (!base) fail(file, "MuJoCo's MJCF of this URDF has no body: the URDF has no link with mass");
  if (base->NextSiblingElement("body"))
    fail(file, "the URDF has more than one root link (MuJoCo's MJCF has several bodies in the world)");
  const bool hasJoint = base->FirstChildElement("freejoint") || base->FirstChildElement("joint");
  if (!hasJoint) base->InsertFirstChild(mjcf.NewElement("freejoint"));
  // MuJoCo writes the inertials the URDF gave; a body it wrote without one must read back as the
  // URDF reader compiled it (massless, unless the URDF asked for mass from geoms).
  XMLElement* mjcf_compiler = mjcf.RootElement()->FirstChildElement("compiler");
  if (!mjcf_compiler) {
    mjcf_compiler = mjcf.NewElement("compiler");
    mjcf.RootElement()->InsertFirstChild(mjcf_compiler);
  }
  mjcf_compiler->SetAttribute("inertiafromgeom", inertia_from_geom.c_str());
  tinyxml2::XMLPrinter printer;
  mjcf.Print(&printer);
  return printer.CStr();
}

// Stage 1: the file parsed into doc as MJCF (a URDF through MuJoCo's URDF reader), its includes
// inlined; returns the <mujoco> root.
XMLElement* loadModelXml(XMLDocument& doc, const std::string& file, PreparedModel& out) {
  loadXmlFile(doc, file);
  if (!doc.RootElement()) fail(file, "empty XML file");
  if (std::string(doc.RootElement()->Name()) == "robot") {
    out.from_urdf = true;
    const std::string mjcf = urdfToMjcf(file, out.urdf_effort_Nm);
    doc.Clear();
    if (doc.Parse(mjcf.c_str()) != tinyxml2::XML_SUCCESS) fail(file, "MuJoCo's MJCF of this URDF does not parse");
    out.notes.push_back("URDF read by MuJoCo's URDF reader (fusestatic off, links without <inertial> massless, "
                        "visual elements discarded), written back as MJCF, its root link given a free joint");
  } else if (std::string(doc.RootElement()->Name()) != "mujoco") {
    fail(file, "neither MJCF (<mujoco>) nor URDF (<robot>)");
  }
  XMLElement* root = doc.RootElement();
  inlineIncludes(doc, root, fs::path(file).parent_path(), 0);
  return root;
}

// Where the model's asset files are, and whether bodies without <inertial> take their mass from geoms.
struct AssetDirs {
  fs::path meshdir, texturedir;
  bool inertia_from_geom = false;
};

// Stage 2: the compiler's asset folders made absolute, so the compiled text finds the files the
// user's file names.
// A model may have several <compiler> elements (a scene's and its included robot's); MuJoCo applies
// them in order, so the last one to set an attribute wins. They are merged into the last.
AssetDirs absoluteAssetDirs(XMLDocument& doc, XMLElement* root, const fs::path& dir, const std::string& file) {
  std::vector<XMLElement*> compilers;
  for (XMLElement* c = root->FirstChildElement("compiler"); c; c = c->NextSiblingElement("compiler")) compilers.push_back(c);
  if (compilers.empty()) {
    compilers.push_back(doc.NewElement("compiler"));
    root->InsertFirstChild(compilers.back());
  }
  XMLElement* compiler = compilers.back();
  for (std::size_t i = compilers.size() - 1; i-- > 0;)
    for (const tinyxml2::XMLAttribute* a = compilers[i]->FirstAttribute(); a; a = a->Next())
      if (!compiler->Attribute(a->Name())) compiler->SetAttribute(a->Name(), a->Value());
  for (std::size_t i = 0; i + 1 < compilers.size(); ++i) root->DeleteChild(compilers[i]);
  if (const char* c = compiler->Attribute("coordinate"); c && std::string(c) == "global")
    fail(file, "the model is written in global coordinates (<compiler coordinate=\"global\">), and tailsim attaches "
               "the tail in a body's local frame: convert it to local coordinates first, e.g. with MuJoCo 2.2's sample "
               "`mujoco-compile model.xml model_local.xml` (it writes the compiled model back as MJCF, in local "
               "coordinates), and import that file");
  auto absDir = [&](const char* attr) {
    const char* v = compiler->Attribute(attr);
    const fs::path p = v ? fs::path(v) : fs::path();
    const fs::path a = p.is_absolute() ? p : (dir / p).lexically_normal();
    std::string text = a.string();
    if (text.empty() || text.back() != '/') text += '/';
    compiler->SetAttribute(attr, text.c_str());
    return a;
  };
  AssetDirs d;
  const char* assetdir = compiler->Attribute("assetdir");
  d.meshdir = compiler->Attribute("meshdir") || !assetdir ? absDir("meshdir") : absDir("assetdir");
  d.texturedir =
      compiler->Attribute("texturedir") || !assetdir ? absDir("texturedir") : fs::path(compiler->Attribute("assetdir"));
  if (assetdir) absDir("assetdir");
  d.inertia_from_geom = compiler->Attribute("inertiafromgeom") &&
                        std::string(compiler->Attribute("inertiafromgeom")) == "true";
  return d;
}

// The assets whose files are missing.
struct MissingAssets {
  std::map<std::string, std::string> mesh;  // mesh name -> the missing file
  std::set<std::string> texture;
  std::vector<XMLElement*> elements;  // their <mesh> and <texture> elements, to drop
};

// Stage 3: the missing mesh and texture files (a missing hfield or skin file is an error); the
// materials lose their missing textures.
MissingAssets findMissingAssets(XMLElement* root, const AssetDirs& dirs, const std::string& file) {
  MissingAssets m;
  for (XMLElement* asset = root->FirstChildElement("asset"); asset; asset = asset->NextSiblingElement("asset")) {
    for (XMLElement* e = asset->FirstChildElement(); e; e = e->NextSiblingElement()) {
      const std::string tag = e->Name();
      if (tag != "mesh" && tag != "texture" && tag != "hfield" && tag != "skin") continue;
      const fs::path base = tag == "texture" ? dirs.texturedir : dirs.meshdir;
      std::vector<std::string> files;
      for (const char* a : {"file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"})
        if (const char* f = e->Attribute(a)) files.push_back(f);
      for (const std::string& f : files) {
        const fs::path p = fs::path(f).is_absolute() ? fs::path(f) : base / f;
        if (isFile(p)) continue;
        const std::string name = e->Attribute("name") ? e->Attribute("name") : stemOf(f);
        if (tag == "mesh") m.mesh[name] = p.string();
        else if (tag == "texture") m.texture.insert(name);
        else fail(file, "<" + tag + "> '" + name + "': file " + p.string() + " is missing");
        m.elements.push_back(e);
        break;
      }
    }
  }
  if (!m.texture.empty()) {
    std::vector<XMLElement*> materials;
    forEachElement(root, [&](XMLElement* e) {
      if (std::string(e->Name()) == "material" && e->Attribute("texture") && m.texture.count(e->Attribute("texture")))
        materials.push_back(e);
    });
    for (XMLElement* mat : materials) mat->DeleteAttribute("texture");
  }
  return m;
}

// Whether a geom can collide: contype or conaffinity (from the geom or its default classes) not 0.
bool collides(const Defaults& defaults, XMLElement* gm) {
  const char* ct = defaults.geomAttr(gm, "contype");
  const char* ca = defaults.geomAttr(gm, "conaffinity");
  return (ct ? std::atoi(ct) : 1) != 0 || (ca ? std::atoi(ca) : 1) != 0;
}

bool isPlane(const Defaults& defaults, XMLElement* gm) {
  const char* type = defaults.geomAttr(gm, "type");
  return type && std::string(type) == "plane";
}

// Stage 4: the geoms that use a missing mesh: returned to be dropped when they cannot collide;
// otherwise an error (also when their body's mass comes from its geoms).
std::vector<XMLElement*> geomsWithoutMesh(const std::vector<XMLElement*>& geoms, const Defaults& defaults,
                                          MissingAssets& missing, const AssetDirs& dirs, const std::string& file) {
  std::vector<std::string> colliding;
  std::vector<XMLElement*> drop;
  for (XMLElement* gm : geoms) {
    const char* mesh = defaults.geomAttr(gm, "mesh");
    if (!mesh || !missing.mesh.count(mesh)) continue;
    const bool can_collide = collides(defaults, gm);
    XMLElement* body = gm->Parent() ? gm->Parent()->ToElement() : nullptr;
    const std::string bodyName = body && body->Attribute("name") ? body->Attribute("name") : "world";
    const std::string geomName =
        gm->Attribute("name") ? "'" + std::string(gm->Attribute("name")) + "'" : "(unnamed, mesh '" + std::string(mesh) + "')";
    if (can_collide) {
      colliding.push_back("geom " + geomName + " in body '" + bodyName + "' collides but its mesh file " +
                          missing.mesh[mesh] + " is missing");
      continue;
    }
    const bool massFromGeoms = dirs.inertia_from_geom || (body && !body->FirstChildElement("inertial"));
    if (massFromGeoms && std::string(body ? body->Name() : "") == "body")
      fail(file, "geom " + geomName + " in body '" + bodyName + "' has a missing mesh file " + missing.mesh[mesh] +
                     " and the body's mass and inertia come from its geoms (no <inertial>): supply the file");
    drop.push_back(gm);
  }
  if (!colliding.empty()) {
    std::string msg = std::to_string(colliding.size()) + " colliding geom" + (colliding.size() > 1 ? "s have" : " has") +
                      " a missing mesh file: ";
    for (std::size_t i = 0; i < colliding.size() && i < 5; ++i) msg += (i ? "; " : "") + colliding[i];
    if (colliding.size() > 5) msg += "; and " + std::to_string(colliding.size() - 5) + " more";
    fail(file, msg + ". Supply the mesh files (meshdir " + dirs.meshdir.string() +
                   "), or make such geoms visual-only (contype=\"0\" conaffinity=\"0\")");
  }
  return drop;
}

// Stage 5: every joint named (the stance is carried by name into a model with a tail).
void nameJoints(XMLElement* world) {
  int unnamed = 0;
  forEachElement(world, [&](XMLElement* e) {
    const std::string tag = e->Name();
    if ((tag == "joint" || tag == "freejoint") && !e->Attribute("name"))
      e->SetAttribute("name", ("tailsim_joint" + std::to_string(++unnamed)).c_str());
  });
}

// Whether the model has a plane; out.floor_geom names the first (empty when unnamed).
bool findFloor(const std::vector<XMLElement*>& geoms, const Defaults& defaults, PreparedModel& out) {
  bool hasPlane = false;
  for (XMLElement* gm : geoms)
    if (isPlane(defaults, gm)) {
      hasPlane = true;
      if (out.floor_geom.empty()) out.floor_geom = gm->Attribute("name") ? gm->Attribute("name") : "";
    }
  return hasPlane;
}

// Stage 3b: every later <worldbody> (a scene file's, after an included robot's) moved into the
// first, in order, as MuJoCo merges them: the floor, the geoms and the bodies are all in one place.
void mergeWorldbodies(XMLElement* world) {
  for (XMLElement* w = world->NextSiblingElement("worldbody"); w; w = world->NextSiblingElement("worldbody")) {
    while (tinyxml2::XMLNode* c = w->FirstChild()) world->InsertEndChild(c);
    w->Parent()->DeleteChild(w);
  }
}

// Stage 6: a floor when the model has none (a robot file without its scene), or a name for its
// unnamed plane; out.floor_geom names it.
void ensureFloor(XMLDocument& doc, XMLElement* world, const std::vector<XMLElement*>& geoms, const Defaults& defaults,
                 bool hasPlane, const std::string& file, PreparedModel& out) {
  if (hasPlane && !out.floor_geom.empty()) return;
  if (hasPlane) {
    // The model's plane has no name: name it.
    for (XMLElement* gm : geoms)
      if (isPlane(defaults, gm)) {
        gm->SetAttribute("name", "tailsim_floor");
        break;
      }
  } else {
    // A ground that is not a plane (a box, a height field) would sit beside or above the added
    // plane: the robot would stand on either, or inside the box, with no sign of it.
    for (XMLElement* gm : geoms) {
      if (gm->Parent() != world) continue;  // a geom of the world body: static scenery
      if (!collides(defaults, gm)) continue;
      const char* type = defaults.geomAttr(gm, "type");
      fail(file, "the model has no plane to stand on, but a static colliding geom " +
                     (gm->Attribute("name") ? "'" + clipped(gm->Attribute("name")) + "'" : std::string("(unnamed)")) +
                     " (" + (type ? type : "sphere") +
                     (gm->GetLineNum() > 0 ? ", line " + std::to_string(gm->GetLineNum()) : std::string()) +
                     "): tailsim stands the robot on a plane; make the ground a plane (<geom type=\"plane\" size=\"0 0 "
                     "1\"/> at its top), or remove it to stand the robot on the plane tailsim adds at z = 0");
    }
    XMLElement* floor = doc.NewElement("geom");
    floor->SetAttribute("name", "tailsim_floor");
    floor->SetAttribute("type", "plane");
    floor->SetAttribute("size", "0 0 1");
    world->InsertFirstChild(floor);
    out.notes.push_back("added a floor (plane, MuJoCo's default friction 1): the model has none");
  }
  out.floor_geom = "tailsim_floor";
}

}  // namespace

bool isPositionServo(const mjModel* m, int a) {
  return m->actuator_trntype[a] == mjTRN_JOINT && m->actuator_biastype[a] == mjBIAS_AFFINE &&
         m->actuator_gaintype[a] == mjGAIN_FIXED && m->actuator_gainprm[mjNGAIN * a] > 0.0 &&
         m->actuator_biasprm[mjNBIAS * a + 1] < 0.0;
}

double servoCtrlPerRad(const mjModel* m, int a) {
  // force = kp ctrl + b0 + b1 length + b2 velocity, length = gear q (a joint transmission)
  return -m->actuator_biasprm[mjNBIAS * a + 1] * m->actuator_gear[6 * a] / m->actuator_gainprm[mjNGAIN * a];
}

double servoCtrlFor(const mjModel* m, int a, double q) {
  return -m->actuator_biasprm[mjNBIAS * a] / m->actuator_gainprm[mjNGAIN * a] + servoCtrlPerRad(m, a) * q;
}

// The stages in order: parse, absolute asset folders, missing assets, geoms without their mesh,
// joint names, floor, print.
PreparedModel prepareRobotModel(const std::string& file_in) {
  PreparedModel out;
  out.source = fs::absolute(file_in).lexically_normal().string();
  const std::string& file = out.source;
  std::error_code ec;
  if (fs::exists(file, ec) && !isFile(file)) fail(file, "the model file is not a regular file (a folder, a device or a FIFO)");
  if (!isFile(file)) fail(file, "model file not found");
  XMLDocument doc;
  XMLElement* root = loadModelXml(doc, file, out);
  const AssetDirs dirs = absoluteAssetDirs(doc, root, fs::path(file).parent_path(), file);
  MissingAssets missing = findMissingAssets(root, dirs, file);
  const Defaults defaults(root);
  XMLElement* world = root->FirstChildElement("worldbody");
  if (!world) fail(file, "no <worldbody>");
  mergeWorldbodies(world);
  std::vector<XMLElement*> geoms;
  forEachElement(world, [&](XMLElement* e) {
    if (std::string(e->Name()) == "geom") geoms.push_back(e);
  });
  const bool hasPlane = findFloor(geoms, defaults, out);
  const std::vector<XMLElement*> dropGeoms = geomsWithoutMesh(geoms, defaults, missing, dirs, file);
  for (XMLElement* gm : dropGeoms) gm->Parent()->DeleteChild(gm);
  // The later stages read `geoms`: the deleted ones leave it (they would be freed elements).
  geoms.erase(std::remove_if(geoms.begin(), geoms.end(),
                             [&](XMLElement* gm) { return std::find(dropGeoms.begin(), dropGeoms.end(), gm) != dropGeoms.end(); }),
              geoms.end());
  for (XMLElement* a : missing.elements) a->Parent()->DeleteChild(a);
  out.dropped_geoms = static_cast<int>(dropGeoms.size());
  out.dropped_textures = static_cast<int>(missing.texture.size());
  if (out.dropped_geoms || out.dropped_textures)
    out.notes.push_back("dropped " + std::to_string(out.dropped_geoms) + " non-colliding geom" +
                        (out.dropped_geoms == 1 ? "" : "s") + " whose mesh file is missing and " +
                        std::to_string(out.dropped_textures) + " texture" + (out.dropped_textures == 1 ? "" : "s") +
                        " whose file is missing (their materials keep their colour)");
  nameJoints(world);
  ensureFloor(doc, world, geoms, defaults, hasPlane, file, out);
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  out.xml = printer.CStr();
  return out;
}

namespace {

// Lowest z of a geom's surface (spheres, capsules, cylinders, boxes exactly; others by bounding sphere).
double lowestZ(const mjModel* m, const mjData* d, int g) {
  const double* p = d->geom_xpos + 3 * g;
  const double* R = d->geom_xmat + 9 * g;  // row-major; column k = geom axis k in world
  const double* s = m->geom_size + 3 * g;
  switch (m->geom_type[g]) {
    case mjGEOM_SPHERE: return p[2] - s[0];
    case mjGEOM_CAPSULE: return p[2] - std::abs(R[8]) * s[1] - s[0];
    case mjGEOM_CYLINDER: return p[2] - std::abs(R[8]) * s[1] - s[0] * std::sqrt(std::max(0.0, 1.0 - R[8] * R[8]));
    case mjGEOM_BOX: return p[2] - std::abs(R[6]) * s[0] - std::abs(R[7]) * s[1] - std::abs(R[8]) * s[2];
    default: return p[2] - m->geom_rbound[g];
  }
}

struct Stance {
  std::vector<double> qpos;                  // nq
  std::vector<std::pair<int, double>> held;  // (joint id, target angle) of every actuated hinge/slide
  std::string words;
};

// The stance: a keyframe (named, or `home`) or qpos0, with the spec's joint angles over it.
Stance stanceOf(const mjModel* m, const RobotModelSpec& spec, const std::string& file) {
  Stance s;
  s.qpos.assign(m->qpos0, m->qpos0 + m->nq);
  std::string key = spec.keyframe;
  if (key.empty() && mj_name2id(m, mjOBJ_KEY, "home") >= 0) key = "home";
  std::string names;  // the model's keyframes, for the errors
  for (int i = 0; i < m->nkey; ++i) names += (names.empty() ? "" : ", ") + std::string(mj_id2name(m, mjOBJ_KEY, i) ? mj_id2name(m, mjOBJ_KEY, i) : "?");
  if (!key.empty()) {
    const int k = mj_name2id(m, mjOBJ_KEY, key.c_str());
    if (k < 0) fail(file, "no keyframe named '" + clipped(key) + "' (keyframes: " + (names.empty() ? "none" : names) + ")", "robot.stance");
    s.qpos.assign(m->key_qpos + k * m->nq, m->key_qpos + (k + 1) * m->nq);
    s.words = "keyframe '" + key + "'";
  } else if (spec.joint_angles_rad.empty()) {
    fail(file, "no stance: the model has no `home` keyframe (keyframes: " + (names.empty() ? "none" : names) +
                   "); name a keyframe or give the joint angles of its standing pose (docs/your-robot.md)",
         "robot.stance");
  } else {
    s.words = "the model's reference pose (qpos0)";
  }
  for (const auto& [name, angle] : spec.joint_angles_rad) {
    const int j = mj_name2id(m, mjOBJ_JOINT, name.c_str());
    if (j < 0) fail(file, "stance: no joint named '" + clipped(name) + "'", "robot.stance");
    if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE)
      fail(file, "stance: joint '" + clipped(name) + "' is not a hinge or slide", "robot.stance");
    if (m->jnt_limited[j] && (angle < m->jnt_range[2 * j] || angle > m->jnt_range[2 * j + 1])) {
      const bool hinge = m->jnt_type[j] == mjJNT_HINGE;
      auto shown = [&](double v) { return g6(hinge ? units::degrees(v) : v); };
      fail(file, "stance: joint '" + clipped(name) + "' at " + shown(angle) + (hinge ? " deg" : " m") +
                     " is outside its range [" + shown(m->jnt_range[2 * j]) + ", " + shown(m->jnt_range[2 * j + 1]) +
                     "]" + (hinge ? " deg" : " m"),
           "robot.stance");
    }
    s.qpos[m->jnt_qposadr[j]] = angle;
  }
  if (!spec.joint_angles_rad.empty())
    s.words += " with " + std::to_string(spec.joint_angles_rad.size()) + " joint angle" +
               (spec.joint_angles_rad.size() == 1 ? "" : "s") + " given";
  return s;
}

// The robot: the body with a free joint, or, in a scene with several, the one whose tree holds the
// tail mount's body (tail.mount.body); several and no mount body to choose by is an error.
int rootBody(const mjModel* m, const RobotModelSpec& spec, const std::string& file) {
  std::vector<int> free;
  for (int j = 0; j < m->njnt; ++j)
    if (m->jnt_type[j] == mjJNT_FREE) free.push_back(m->jnt_bodyid[j]);
  if (free.empty()) fail(file, "no free joint: a standing robot needs a floating base (<freejoint/>)");
  if (free.size() == 1) return free.front();
  std::string names;
  for (int b : free) names += (names.empty() ? "'" : ", '") + clipped(mj_id2name(m, mjOBJ_BODY, b) ? mj_id2name(m, mjOBJ_BODY, b) : "?") + "'";
  if (!spec.mount.body.empty()) {
    const int mb = mj_name2id(m, mjOBJ_BODY, spec.mount.body.c_str());
    if (mb < 0) fail(file, "tail mount: no body named '" + clipped(spec.mount.body) + "'", "tail.mount.body");
    for (int b : free)
      if (m->body_rootid[mb] == m->body_rootid[b]) return b;
  }
  fail(file, std::to_string(free.size()) + " bodies have a free joint (" + names +
                 "): name the robot's body the tail goes on with tail.mount.body (--mount-body), and the robot is that "
                 "body's tree",
       "tail.mount.body");
}

// The torque limit of joint j when tailsim's PD holds it: the smallest of its joint actuators'
// (motors: |gear| times the larger |end| of ctrlrange or forcerange, where limited) and the URDF's
// effort; HUGE_VAL when it has none.
double pdTorqueLimit(const mjModel* m, int j, const std::map<std::string, double>& efforts) {
  double limit = HUGE_VAL;
  for (int a = 0; a < m->nu; ++a) {
    if (m->actuator_trntype[a] != mjTRN_JOINT || m->actuator_trnid[2 * a] != j) continue;
    const double gear = std::abs(m->actuator_gear[6 * a]);
    if (m->actuator_ctrllimited[a] && m->actuator_gaintype[a] == mjGAIN_FIXED && m->actuator_biastype[a] == mjBIAS_NONE)
      limit = std::min(limit, gear * std::abs(m->actuator_gainprm[mjNGAIN * a]) *
                                  std::max(std::abs(m->actuator_ctrlrange[2 * a]), std::abs(m->actuator_ctrlrange[2 * a + 1])));
    if (m->actuator_forcelimited[a])
      limit = std::min(limit, gear * std::max(std::abs(m->actuator_forcerange[2 * a]), std::abs(m->actuator_forcerange[2 * a + 1])));
  }
  const char* name = mj_id2name(m, mjOBJ_JOINT, j);
  if (const auto e = name ? efforts.find(name) : efforts.end(); e != efforts.end()) limit = std::min(limit, e->second);
  return limit;
}

// How the legs are held in the stance.
struct LegHold {
  std::vector<int> by_actuator;  // per joint: 1 when a position actuator of the model holds it
  std::vector<double> ctrl;      // the actuators' ctrl: the stance angle for position actuators
  std::vector<int> pd;           // hinge and slide joints held by tailsim's PD
  std::vector<double> pd_limit;  // their torque limits (HUGE_VAL: none) [N m]
  int position_servos = 0;
  int other_actuators = 0;       // joint actuators that are not position servos (motors): ctrl 0
};

// " (its torque kept within the joint's own limit on k of them: ...)" for the stance line, "" when
// none has a limit.
std::string pdLimitWords(const LegHold& h) {
  int n = 0;
  double lo = HUGE_VAL, hi = 0.0;
  for (double l : h.pd_limit)
    if (std::isfinite(l)) ++n, lo = std::min(lo, l), hi = std::max(hi, l);
  if (n == 0) return "";
  return " (its torque kept within the joint's own limit on " + std::to_string(n) + " of them: " + g6(lo) +
         (hi > lo ? " to " + g6(hi) : std::string()) + " N m, from the model's motors or the URDF's effort)";
}

// Legs held by the model's actuators: position actuators (bias -kp q) get the ctrl that holds the
// stance angle (servoCtrlFor: the angle times the gear for a <position>); a joint without one is
// held by a PD tailsim adds through qfrc_applied. A ctrlrange that leaves out that ctrl is an error
// (MuJoCo would clamp it, and the robot would fall for no reason the user could see).
LegHold holdLegs(const mjModel* m, const Stance& stance, const std::string& file,
                 const std::map<std::string, double>& efforts) {
  LegHold h;
  h.by_actuator.assign(m->njnt, 0);
  h.ctrl.assign(m->nu, 0.0);
  for (int a = 0; a < m->nu; ++a) {
    if (m->actuator_trntype[a] != mjTRN_JOINT) continue;
    const int j = m->actuator_trnid[2 * a];
    if (!isPositionServo(m, a)) {
      ++h.other_actuators;
      continue;
    }
    const double q = stance.qpos[m->jnt_qposadr[j]];
    h.ctrl[a] = servoCtrlFor(m, a, q);
    if (m->actuator_ctrllimited[a] &&
        (h.ctrl[a] < m->actuator_ctrlrange[2 * a] || h.ctrl[a] > m->actuator_ctrlrange[2 * a + 1])) {
      const char* an = mj_id2name(m, mjOBJ_ACTUATOR, a);
      const char* jn = mj_id2name(m, mjOBJ_JOINT, j);
      fail(file, "actuator '" + clipped(an ? an : "#" + std::to_string(a)) + "' cannot hold joint '" +
                     clipped(jn ? jn : "#" + std::to_string(j)) + "' at its stance angle " + g6(units::degrees(q)) +
                     " deg: that needs ctrl " + g6(h.ctrl[a]) + ", outside its ctrlrange [" +
                     g6(m->actuator_ctrlrange[2 * a]) + ", " + g6(m->actuator_ctrlrange[2 * a + 1]) +
                     "]; choose a stance inside it (robot.stance, --joint NAME=DEG) or widen the ctrlrange",
           "robot.stance");
    }
    h.by_actuator[j] = 1;
    ++h.position_servos;
  }
  for (int j = 0; j < m->njnt; ++j)
    if ((m->jnt_type[j] == mjJNT_HINGE || m->jnt_type[j] == mjJNT_SLIDE) && !h.by_actuator[j]) {
      h.pd.push_back(j);
      h.pd_limit.push_back(pdTorqueLimit(m, j, efforts));
    }
  return h;
}

}  // namespace

void addStancePdDamping(mjModel* m, const std::vector<int>& joints) {
  for (int j : joints) m->dof_damping[m->jnt_dofadr[j]] += kStancePdKv;
}

namespace {

constexpr double kStandRestSpeedMps = 1e-3;   // a body at rest moves slower than this [m/s]
constexpr double kStandRestTurnRadps = 0.01;  // ... and turns slower than this [rad/s]
constexpr double kStandMoreS = 0.25;          // standing goes on in steps of this while the body moves [s]
constexpr double kStandMaxExtraS = 3.0;       // ... for at most this beyond settle_s [s]
constexpr double kStandMaxTiltDeg = 30.0;     // a robot tilted further after standing does not stand [deg]
constexpr double kStandMaxSinkShare = 0.3;    // nor one whose body sank more than this share of its start height

// Stage: the stance lifted (or lowered) until the lowest colliding geom is 1 mm above the floor, then
// settled for spec.settle_s with the legs held; r.tilt_deg is the root body's tilt afterwards.
void stand(mjModel* m, mjData* d, const RobotModelSpec& spec, const Stance& stance, const LegHold& hold, int root,
           int floor, const std::string& file, DerivedRobot& r) {
  mju_copy(d->qpos, stance.qpos.data(), m->nq);
  mj_kinematics(m, d);
  const double floorZ = floor >= 0 ? d->geom_xpos[3 * floor + 2] : 0.0;
  double low = 1e300;
  for (int g = 0; g < m->ngeom; ++g)
    if (m->geom_bodyid[g] != 0 && m->body_rootid[m->geom_bodyid[g]] == root && (m->geom_contype[g] || m->geom_conaffinity[g])) low = std::min(low, lowestZ(m, d, g));
  const int freeq = m->jnt_qposadr[m->body_jntadr[root]];
  const double lift = floorZ + 1e-3 - low;
  d->qpos[freeq + 2] += lift;
  const double z0 = d->qpos[freeq + 2];  // the root body's height at the start, 1 mm above the floor
  mju_copy(d->ctrl, hold.ctrl.data(), m->nu);
  addStancePdDamping(m, hold.pd);
  const auto standFor = [&](double seconds) {
    const int steps = static_cast<int>(std::ceil(seconds / m->opt.timestep - 1e-9));
    for (int i = 0; i < steps; ++i) {
      for (std::size_t k = 0; k < hold.pd.size(); ++k) {
        const int qa = m->jnt_qposadr[hold.pd[k]], va = m->jnt_dofadr[hold.pd[k]];
        d->qfrc_applied[va] = stancePdTorque(stance.qpos[qa], d->qpos[qa], hold.pd_limit[k]);
      }
      mj_step(m, d);
    }
  };
  // settle_s, then on in kStandMoreS steps while the body still moves (up to kStandMaxExtraS more):
  // a robot measured while it still rocks gives values that depend on when it was measured.
  const int freev = m->jnt_dofadr[m->body_jntadr[root]];
  const auto speed = [&] { return std::hypot(d->qvel[freev], d->qvel[freev + 1], d->qvel[freev + 2]); };
  const auto turnRate = [&] { return std::hypot(d->qvel[freev + 3], d->qvel[freev + 4], d->qvel[freev + 5]); };
  const auto moving = [&] { return speed() > kStandRestSpeedMps || turnRate() > kStandRestTurnRadps; };
  standFor(spec.settle_s);
  double stood = spec.settle_s;
  while (moving() && stood < spec.settle_s + kStandMaxExtraS - 1e-9) {
    standFor(kStandMoreS);
    stood += kStandMoreS;
  }
  r.stood_s = stood;
  r.notes.push_back("stance started " + g6(1e3 * std::abs(low - floorZ)) +
                    (low >= floorZ ? " mm above" : " mm below") + " the floor (lowest colliding geom); moved " +
                    g6(1e3 * lift) + " mm to start 1 mm above it, then stood " + g6(stood) + " s" +
                    (stood > spec.settle_s ? " (settle_s " + g6(spec.settle_s) + " s, then on until the body rested)" : ""));
  if (moving())
    r.notes.push_back("the body still moves after standing " + g6(stood) + " s (" + g6(1e3 * speed()) + " mm/s, " +
                      g6(units::degrees(turnRate())) + " deg/s): the values below are of a robot that has not come to "
                      "rest (its legs' servos may be undamped)");
  mj_forward(m, d);
  if (warningCount(d) > 0)
    fail(file, "MuJoCo warnings while standing: " + describeWarnings(d) + " (the robot's servos or contacts are too "
               "stiff for the model's timestep, " + g6(m->opt.timestep) + " s: lower <option timestep> or the actuators' kp)");
  std::string saturated;  // PD-held joints whose torque limit holds them back at the end
  int n_saturated = 0;
  for (std::size_t k = 0; k < hold.pd.size(); ++k) {
    const int qa = m->jnt_qposadr[hold.pd[k]];
    if (std::abs(kStancePdKp * (stance.qpos[qa] - d->qpos[qa])) < hold.pd_limit[k]) continue;
    const char* n = mj_id2name(m, mjOBJ_JOINT, hold.pd[k]);
    if (n_saturated++ < 4) saturated += (saturated.empty() ? "" : ", ") + clipped(n ? n : "?");
  }
  if (n_saturated > 0)
    r.stance += "; after standing, " + std::to_string(n_saturated) + " of them at their torque limit (" + saturated +
                (n_saturated > 4 ? ", ..." : "") + "): the legs cannot hold the stance";
  const double* Rroot = d->xmat + 9 * root;
  r.tilt_deg = units::degrees(std::acos(std::clamp(Rroot[8], -1.0, 1.0)));
  // A robot that collapsed (its legs gave way, or the stance cannot be stood in) lies on its body:
  // what touches the floor then is not its feet.
  const double sank = z0 - d->qpos[freeq + 2], start_h = z0 - floorZ;
  if (r.tilt_deg > kStandMaxTiltDeg || (start_h > 0.0 && sank > kStandMaxSinkShare * start_h))
    fail(file, "the robot does not stand in " + r.stance + ": after " + g6(stood) + " s its body has sunk " +
                   g6(1e3 * sank) + " mm of the " + g6(1e3 * start_h) + " mm it started above the floor and is tilted " +
                   g6(r.tilt_deg) + " deg (limits " + g6(100 * kStandMaxSinkShare) + " % and " + g6(kStandMaxTiltDeg) +
                   " deg): its legs do not hold the stance (servos too weak or too soft for its weight, or a stance "
                   "it cannot stand in)",
         "robot.stance");
}

// A geom's name, or "geom #k of body 'b'" for an unnamed one.
std::string geomName(const mjModel* m, int g) {
  const char* n = mj_id2name(m, mjOBJ_GEOM, g);
  return n ? std::string(n) : "geom #" + std::to_string(g) + " of body '" +
                                  std::string(mj_id2name(m, mjOBJ_BODY, m->geom_bodyid[g]) ? mj_id2name(m, mjOBJ_BODY, m->geom_bodyid[g]) : "?") + "'";
}

// Stage: the feet: the named geoms, or the robot's geoms touching the floor (a foot body's geoms within
// kFootMergeM of each other count once, its lowest); 3 or 4 of them.
constexpr double kFootMergeM = 0.05;  // [m] horizontal, between geom centres
// A geom as a message names it: 'name', or geom #k of body 'b' for an unnamed one (no quotes around).
std::string quotedGeom(const mjModel* m, int g) {
  const char* n = mj_id2name(m, mjOBJ_GEOM, g);
  return n ? "'" + clipped(n) + "'" : clipped(geomName(m, g));
}

// Geoms g and h are one foot: the same geom, or two of one body within kFootMergeM of each other.
bool sameFoot(const mjModel* m, const mjData* d, int g, int h) {
  const double* a = d->geom_xpos + 3 * g;
  const double* b = d->geom_xpos + 3 * h;
  return g == h || (m->geom_bodyid[g] == m->geom_bodyid[h] && std::hypot(a[0] - b[0], a[1] - b[1]) < kFootMergeM);
}

// The robot's (root's tree's) geoms touching the floor after standing, a foot body's geoms within
// kFootMergeM of each other as one (its lowest).
std::vector<int> touchingFeet(const mjModel* m, const mjData* d, int floor, int root) {
  std::vector<int> feet;
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    const int other = c.geom1 == floor ? c.geom2 : c.geom2 == floor ? c.geom1 : -1;
    if (other < 0 || c.dist > 1e-3 || m->body_rootid[m->geom_bodyid[other]] != root) continue;
    const auto same = std::find_if(feet.begin(), feet.end(), [&](int g) { return sameFoot(m, d, g, other); });
    if (same == feet.end()) feet.push_back(other);
    else if (lowestZ(m, d, other) < lowestZ(m, d, *same)) *same = other;
  }
  return feet;
}

// Named feet must be the ones standing: each touches the floor, and no other geom does (one
// within kFootMergeM of a named foot on its body counts as that foot).
void checkNamedFeet(const mjModel* m, const mjData* d, const std::vector<int>& named, const std::vector<int>& touching,
                    const std::string& file) {
  for (int g : named)
    if (std::none_of(touching.begin(), touching.end(), [&](int t) { return sameFoot(m, d, g, t); }))
      fail(file, "feet: " + quotedGeom(m, g) + " does not touch the floor after standing: name the geoms the robot "
                 "stands on (or leave feet: out to take the touching ones)",
           "robot.feet");
  for (int t : touching)
    if (std::none_of(named.begin(), named.end(), [&](int g) { return sameFoot(m, d, g, t); }))
      fail(file, "feet: " + quotedGeom(m, t) + " also touches the floor after standing but is not named: name "
                 "every foot the robot stands on",
           "robot.feet");
}

std::vector<int> findFeet(const mjModel* m, const mjData* d, const RobotModelSpec& spec, int floor, int root,
                          const std::string& file, const DerivedRobot& r) {
  std::vector<int> feet = touchingFeet(m, d, floor, root);
  if (!spec.feet.empty()) {
    std::vector<int> named;
    for (const std::string& n : spec.feet) {
      int g = mj_name2id(m, mjOBJ_GEOM, n.c_str());
      // A body's name stands for its lowest colliding geom (a URDF's geoms have no names).
      if (const int b = g < 0 ? mj_name2id(m, mjOBJ_BODY, n.c_str()) : -1; b >= 0) {
        for (int k = 0; k < m->ngeom; ++k)
          if (m->geom_bodyid[k] == b && (m->geom_contype[k] || m->geom_conaffinity[k]) &&
              (g < 0 || lowestZ(m, d, k) < lowestZ(m, d, g)))
            g = k;
        if (g < 0) fail(file, "feet: body '" + clipped(n) + "' has no colliding geom", "robot.feet");
      }
      if (g < 0) fail(file, "feet: no geom or body named '" + clipped(n) + "'", "robot.feet");
      named.push_back(g);
    }
    if (named.size() < 3 || named.size() > 4)
      fail(file, "feet: names " + std::to_string(named.size()) + " geoms; name the 3 or 4 feet the robot stands on",
           "robot.feet");
    checkNamedFeet(m, d, named, feet, file);
    feet = named;
  }
  if (feet.size() < 3 || feet.size() > 4) {
    std::string names;
    for (int g : feet) names += (names.empty() ? "" : ", ") + geomName(m, g);
    fail(file, "after standing " + g6(r.stood_s) + " s in " + r.stance + ", the robot touches the floor with " +
                   std::to_string(feet.size()) + " geom" + (feet.size() == 1 ? "" : "s") +
                   (names.empty() ? "" : " (" + names + ")") +
                   "; a quadruped stands on 3 or 4 feet: check the stance (tilt " + g6(r.tilt_deg) +
                   " deg) or name the feet with feet: [...] (geom names, or the names of the foot bodies)",
         "robot.feet");
  }
  return feet;
}

// The robot's mass and COM (world frame).
struct MassCentre {
  double M = 0.0, c[3] = {0, 0, 0};
};

// Stage: mass, COM and composite I_zz about the COM of the robot's bodies (the root body's tree, not
// the world nor other bodies of a scene), into r.quadruped; MuJoCo's own figures for comparison.
MassCentre massProperties(const mjModel* m, const mjData* d, int root, DerivedRobot& r) {
  auto robotBody = [&](int b) { return b > 0 && m->body_rootid[b] == root; };
  MassCentre mc;
  double& M = mc.M;
  double* c = mc.c;
  for (int b = 1; b < m->nbody; ++b) {
    if (!robotBody(b)) continue;
    M += m->body_mass[b];
    for (int k = 0; k < 3; ++k) c[k] += m->body_mass[b] * d->xipos[3 * b + k];
  }
  for (int k = 0; k < 3; ++k) c[k] /= M;
  double izz = 0.0;
  for (int b = 1; b < m->nbody; ++b) {
    if (!robotBody(b)) continue;
    const double* R = d->ximat + 9 * b;
    const double* I = m->body_inertia + 3 * b;
    const double dx = d->xipos[3 * b] - c[0], dy = d->xipos[3 * b + 1] - c[1];
    izz += R[6] * R[6] * I[0] + R[7] * R[7] * I[1] + R[8] * R[8] * I[2] + m->body_mass[b] * (dx * dx + dy * dy);
  }
  r.mujoco_subtreemass_kg = m->body_subtreemass[root];
  for (int b = 1; b < m->nbody; ++b)
    if (robotBody(b)) r.mujoco_cinert_izz_kgm2 += d->cinert[10 * b + 2];
  r.quadruped.mass_kg = M;
  r.quadruped.izz_kgm2 = izz;
  return mc;
}

// The tail mount's body: tail.mount.body, else the root; part of the robot's tree. A body that a
// joint moves relative to the root is noted.
int mountBody(const mjModel* m, const RobotModelSpec& spec, int root, const std::string& file, DerivedRobot& r) {
  const int mount = spec.mount.body.empty() ? root : mj_name2id(m, mjOBJ_BODY, spec.mount.body.c_str());
  if (mount < 0) fail(file, "tail mount: no body named '" + clipped(spec.mount.body) + "'", "tail.mount.body");
  if (m->body_rootid[mount] != root)
    fail(file, "tail mount: body '" + clipped(spec.mount.body) + "' is not part of the robot (the tree of '" +
                   clipped(mj_id2name(m, mjOBJ_BODY, root) ? mj_id2name(m, mjOBJ_BODY, root) : "?") + "')",
         "tail.mount.body");
  r.mount_body = mj_id2name(m, mjOBJ_BODY, mount) ? mj_id2name(m, mjOBJ_BODY, mount) : "";
  for (int b = mount; b != root; b = m->body_parentid[b])
    if (m->body_jntnum[b] > 0) {
      r.notes.push_back("the tail is mounted on '" + clipped(r.mount_body) + "', which a joint of body '" +
                        clipped(mj_id2name(m, mjOBJ_BODY, b) ? mj_id2name(m, mjOBJ_BODY, b) : "?") +
                        "' moves relative to the robot's root body: the planar frame and d_Q2B_m are taken in the "
                        "stance, and the tail's base moves with that leg");
      break;
    }
  return mount;
}

// The feet's order in the planar frame (fp: their positions, (mx, my) their centroid): FL, FR, RR,
// RL (front = x above the centroid, left = y above it), or 3 feet front to back.
std::vector<int> footOrder(const std::vector<std::array<double, 2>>& fp, double mx, double my, const std::string& file) {
  const int nf = static_cast<int>(fp.size());
  std::vector<int> order(nf, -1);
  if (nf == 4) {
    for (int i = 0; i < 4; ++i) {
      const bool front = fp[i][0] > mx, left = fp[i][1] > my;
      const int slot = front ? (left ? 0 : 1) : (left ? 3 : 2);
      if (order[slot] >= 0) fail(file, "the feet do not stand at the corners of a quadrilateral (two feet are " +
                                           std::string(front ? "front " : "rear ") + (left ? "left" : "right") + ")",
                              "robot.feet");
      order[slot] = i;
    }
  } else {
    for (int i = 0; i < nf; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return fp[a][0] > fp[b][0]; });
  }
  return order;
}

// Stage: the planar frame (the mount body's x axis turned by the mount yaw, projected on the floor,
// origin at the COM), the feet ordered FL, FR, RR, RL in it (3 feet: front to back), and the
// quadruped's lengths. Returns the difference of the left and right foot spacings.
double planarGeometry(const mjModel* m, const mjData* d, const RobotModelSpec& spec, int root, const std::vector<int>& feet,
                      const MassCentre& mc, const std::string& file, DerivedRobot& r) {
  const double* c = mc.c;
  const int mount = mountBody(m, spec, root, file, r);
  const double* Rm = d->xmat + 9 * mount;
  const double psi = std::atan2(Rm[3], Rm[0]) + spec.mount.yaw_rad;
  const double ex[2] = {std::cos(psi), std::sin(psi)}, ey[2] = {-std::sin(psi), std::cos(psi)};
  auto planar = [&](const double* p) {
    const double dx = p[0] - c[0], dy = p[1] - c[1];
    return std::array<double, 2>{dx * ex[0] + dy * ex[1], dx * ey[0] + dy * ey[1]};
  };
  std::vector<std::array<double, 2>> fp;
  for (int g : feet) fp.push_back(planar(d->geom_xpos + 3 * g));
  const int nf = static_cast<int>(feet.size());
  double mx = 0.0, my = 0.0;
  for (const auto& p : fp) mx += p[0] / nf, my += p[1] / nf;
  r.foot_count = nf;
  const std::vector<int> order = footOrder(fp, mx, my, file);
  for (int s = 0; s < nf; ++s) {
    const int g = feet[order[s]], b = m->geom_bodyid[g];
    r.feet.push_back(geomName(m, g));
    r.foot_geoms.emplace_back(mj_id2name(m, mjOBJ_BODY, b) ? mj_id2name(m, mjOBJ_BODY, b) : "", g - m->body_geomadr[b]);
  }
  QuadrupedParams& q = r.quadruped;
  double asym = 0.0;
  if (nf == 4) {
    const auto& FL = fp[order[0]];
    const auto& FR = fp[order[1]];
    const auto& RR = fp[order[2]];
    const auto& RL = fp[order[3]];
    q.l_F_m = 0.5 * (FL[0] + FR[0]) - 0.5 * (RL[0] + RR[0]);
    q.w_F_m = 0.5 * (FL[1] + RL[1]) - 0.5 * (FR[1] + RR[1]);
    asym = std::abs((FL[0] - RL[0]) - (FR[0] - RR[0]));
  } else {  // the support triangle's extents: the planar models, which take 4 feet, are not run on it
    q.l_F_m = fp[order[0]][0] - fp[order[2]][0];
    double ylo = 1e300, yhi = -1e300;
    for (const auto& p : fp) ylo = std::min(ylo, p[1]), yhi = std::max(yhi, p[1]);
    q.w_F_m = yhi - ylo;
  }
  q.d_Q2C_m = mx;
  r.lateral_com_to_feet_m = my;
  double footZ = 0.0;
  for (int g : feet) footZ += lowestZ(m, d, g) / nf;
  q.com_height_m = c[2] - footZ;
  double base[3];
  mju_rotVecMat(base, spec.mount.pos_m.data(), d->xmat + 9 * mount);
  for (int k = 0; k < 3; ++k) base[k] += d->xpos[3 * mount + k];
  const auto b = planar(base);
  q.d_Q2B_m = -b[0];
  r.lateral_mount_m = b[1];
  const bool mountGiven = !spec.mount.body.empty() || spec.mount.pos_m != std::array<double, 3>{};
  if (!mountGiven)
    r.notes.push_back("no tail mount given: d_Q2B_m is that of the root body's origin (--mount-pos X,Y,Z sets the tail base)");
  else if (q.d_Q2B_m < 0.0)
    r.notes.push_back("the tail base is in front of the COM (d_Q2B_m < 0): check the mount (pos_m, yaw_deg)");
  return asym;
}

// Stage: the friction coefficient into r.mu: given, else the contacts' own (MuJoCo mixes the
// foot's and the floor's: priority, else the larger), else the foot geoms'. Returns its source.
std::string footFriction(const mjModel* m, const mjData* d, const RobotModelSpec& spec, const std::vector<int>& feet,
                         DerivedRobot& r) {
  double mu_sum = 0.0;
  int nmu = 0;
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& ct = d->contact[i];
    if (std::find(feet.begin(), feet.end(), ct.geom1) != feet.end() || std::find(feet.begin(), feet.end(), ct.geom2) != feet.end()) {
      mu_sum += ct.friction[0];
      ++nmu;
    }
  }
  if (spec.mu >= 0.0) {
    r.mu = spec.mu;
    r.mu_given = true;
    return "given (overrides the foot contacts)";
  }
  if (nmu > 0) {
    r.mu = mu_sum / nmu;
    return "MuJoCo's foot-floor contacts (friction[0], " + std::to_string(nmu) + " contacts)";
  }
  r.mu = 0.0;
  for (int g : feet) r.mu += m->geom_friction[3 * g] / feet.size();
  return "the foot geoms' friction (no contact after standing)";
}

// Stage: r.values, the derived settings with the source of each.
void listValues(const RobotModelSpec& spec, const std::string& muSource, DerivedRobot& r) {
  const QuadrupedParams& q = r.quadruped;
  const std::string stood = " (stance after standing " + g6(r.stood_s) + " s)";
  const std::string frame = "planar frame: body '" + r.mount_body + "' x" +
                            (spec.mount.yaw_rad != 0.0 ? " turned by " + g6(units::degrees(spec.mount.yaw_rad)) + " deg" : "");
  r.values = {
      {"quadruped.mass_kg", q.mass_kg, "kg", "sum of the model's body masses (MuJoCo body_subtreemass of '" + r.root_body + "': " + g6(r.mujoco_subtreemass_kg) + ")"},
      {"quadruped.izz_kgm2", q.izz_kgm2, "kg m^2", "composite I_zz about the COM, legs held" + stood + "; MuJoCo cinert sum " + g6(r.mujoco_cinert_izz_kgm2)},
      {"quadruped.d_Q2C_m", q.d_Q2C_m, "m", "x of the foot centroid from the COM, " + frame},
      {"quadruped.d_Q2B_m", q.d_Q2B_m, "m", "tail base (body '" + r.mount_body + "' + pos_m) behind the COM, " + frame},
      {"quadruped.l_F_m", q.l_F_m, "m", r.foot_count == 4 ? "front feet x - rear feet x (means of each pair)" : "front foot x - rear foot x (3 feet)"},
      {"quadruped.w_F_m", q.w_F_m, "m", r.foot_count == 4 ? "left feet y - right feet y (means of each pair)" : "left-most foot y - right-most foot y (3 feet)"},
      {"quadruped.com_height_m", q.com_height_m, "m", "COM above the feet's lowest points" + stood},
      {"friction.mu_s = mu_d", r.mu, "-", muSource},
      {"gravity_mps2", r.gravity_mps2, "m/s^2", "the model's option gravity"},
  };
}

// Stage: every named joint's settled qpos, hold target and (held by tailsim's PD) name.
void settledJoints(const mjModel* m, const mjData* d, const Stance& stance, const LegHold& hold, DerivedRobot& r) {
  for (int j = 0; j < m->njnt; ++j) {
    const int n = m->jnt_type[j] == mjJNT_FREE ? 7 : m->jnt_type[j] == mjJNT_BALL ? 4 : 1;
    const char* name = mj_id2name(m, mjOBJ_JOINT, j);
    if (!name) continue;
    r.settled_qpos[name].assign(d->qpos + m->jnt_qposadr[j], d->qpos + m->jnt_qposadr[j] + n);
    if (m->jnt_type[j] == mjJNT_HINGE || m->jnt_type[j] == mjJNT_SLIDE) {
      r.hold_target_rad[name] = stance.qpos[m->jnt_qposadr[j]];
      if (!hold.by_actuator[j]) {
        r.pd_joints.push_back(name);
        const auto k = std::find(hold.pd.begin(), hold.pd.end(), j) - hold.pd.begin();
        if (std::isfinite(hold.pd_limit[k])) r.pd_torque_limit_Nm[name] = hold.pd_limit[k];
      }
    }
  }
}

// "file:line" of the first <element> (any element when empty) carrying attribute `attr` (any
// attribute when empty; equal to `value` when that is given) in `file` or the files it includes;
// "" when none.
std::string findInUserFiles(const std::string& file, const std::string& element, const std::string& attr, int depth,
                            const char* value = nullptr) {
  XMLDocument doc;
  if (depth > 8 || doc.LoadFile(file.c_str()) != tinyxml2::XML_SUCCESS || !doc.RootElement()) return "";
  std::string found;
  forEachElement(doc.RootElement(), [&](XMLElement* e) {
    if (!found.empty()) return;
    const std::string name = e->Name();
    const char* a = attr.empty() ? nullptr : e->Attribute(attr.c_str());
    if ((element.empty() || name == element) && (attr.empty() || (a && (!value || std::string(a) == value))))
      found = file + ":" + std::to_string(e->GetLineNum());
    else if (name == "include" && e->Attribute("file")) {
      const fs::path f = e->Attribute("file");
      found = findInUserFiles((f.is_absolute() ? f : fs::path(file).parent_path() / f).string(), element, attr,
                              depth + 1, value);
    }
  });
  return found;
}

// The text between `open` and the next `close` after it in `text`, or "".
std::string between(const std::string& text, const std::string& open, const std::string& close) {
  const std::size_t a = text.find(open);
  if (a == std::string::npos) return "";
  const std::size_t b = text.find(close, a + open.size());
  return b == std::string::npos ? "" : text.substr(a + open.size(), b - a - open.size());
}

// The prepared model compiled by MuJoCo. An attribute or element MuJoCo 2.2's schema does not know
// (MJCF written for MuJoCo 3.x) is an error at its line in the user's file; any other refusal keeps
// MuJoCo's text and names the user's file.
ModelPtr compileUserModel(const PreparedModel& pm) {
  try {
    return loadModelFromXml(pm.xml);
  } catch (const MujocoError& e) {
    const std::string msg = e.what();
    const std::string element = between(msg, "Element '", "'");
    const std::string attr = between(msg, "unrecognized attribute: '", "'");
    const bool unknownElement = msg.find("unrecognized element") != std::string::npos;
    if (!element.empty() && (!attr.empty() || unknownElement)) {
      std::string where = findInUserFiles(pm.source, element, attr, 0);
      if (where.empty()) where = pm.source;
      const std::string what = attr.empty() ? "element <" + element + ">"
                                            : "attribute '" + attr + "' of <" + element + ">";
      throw RobotImportError(where + ": " + what +
                             " is not known to MuJoCo 2.2, the MuJoCo tailsim is built with (the file is "
                             "written for a newer MuJoCo, 3.x): remove it, or use a version of the model "
                             "made for MuJoCo 2.2");
    }
    const std::string prefix = "MuJoCo could not compile the generated MJCF: ";
    // MuJoCo names the object; its line in the user's own file says where to look.
    const std::string object = between(msg, "Object name = ", ",");
    const std::string where = object.empty() ? "" : findInUserFiles(pm.source, "", "name", 0, object.c_str());
    std::string why = (where.empty() ? pm.source : where) +
                      ": MuJoCo 2.2 refuses the model (MuJoCo's line numbers are of tailsim's copy, includes inlined): " +
                      (msg.rfind(prefix, 0) == 0 ? msg.substr(prefix.size()) : msg);
    if (msg.find("has `range` but not `limited`") != std::string::npos)
      why += " (MuJoCo 2.3 and later set `limited` from `range` by themselves: the file is likely written for a newer "
             "MuJoCo; add <compiler autolimits=\"true\"/> to it for MuJoCo 2.2)";
    throw RobotImportError(why);
  }
}

}  // namespace

// The stages in order: prepare and compile the model, the stance and how the legs are held, stand,
// the feet, mass properties, the planar geometry, friction, the values and notes, the settled joints.
DerivedRobot deriveRobot(const RobotModelSpec& spec) {
  DerivedRobot r;
  r.model = prepareRobotModel(spec.file);
  const std::string& file = r.model.source;
  MujocoMessages messages;
  ModelPtr mp = compileUserModel(r.model);
  mjModel* m = mp.get();
  DataPtr dp = makeData(m);
  mjData* d = dp.get();
  r.gravity_mps2 = -m->opt.gravity[2];
  if (!(r.gravity_mps2 > 0.0)) fail(file, "gravity must point down (-z) to stand the robot");

  const int root = rootBody(m, spec, file);
  r.root_body = mj_id2name(m, mjOBJ_BODY, root) ? mj_id2name(m, mjOBJ_BODY, root) : "";
  const Stance stance = stanceOf(m, spec, file);
  r.stance = stance.words;
  if (spec.legs != "servos" && spec.legs != "locked")
    fail(file, "legs: '" + spec.legs + "' is neither servos nor locked", "robot.legs");
  r.legs_locked = spec.legs == "locked";
  const LegHold hold = holdLegs(m, stance, file, r.model.urdf_effort_Nm);
  r.stance += ", legs held by " + std::to_string(hold.position_servos) + " position actuator" +
              (hold.position_servos == 1 ? "" : "s") + " of the model" +
              (hold.pd.empty() ? "" : " and a PD added by tailsim on " + std::to_string(hold.pd.size()) + " joints") +
              pdLimitWords(hold) +
              (hold.other_actuators == 0
                   ? ""
                   : " (the model's " + std::to_string(hold.other_actuators) + " other joint actuator" +
                         (hold.other_actuators == 1 ? " is not a position servo" : "s are not position servos") +
                         ", e.g. torque motors: their ctrl stays 0)");

  const int floor = mj_name2id(m, mjOBJ_GEOM, r.model.floor_geom.c_str());
  stand(m, d, spec, stance, hold, root, floor, file, r);
  const std::vector<int> feet = findFeet(m, d, spec, floor, root, file, r);
  const MassCentre mc = massProperties(m, d, root, r);
  const double asym = planarGeometry(m, d, spec, root, feet, mc, file, r);
  listValues(spec, footFriction(m, d, spec, feet, r), r);
  if (std::abs(r.lateral_com_to_feet_m) > 1e-3)
    r.notes.push_back("the foot centroid is " + g6(1e3 * r.lateral_com_to_feet_m) +
                      " mm to the side of the COM; the planar models take 0");
  if (std::abs(r.lateral_mount_m) > 1e-3)
    r.notes.push_back("the tail base is " + g6(1e3 * r.lateral_mount_m) + " mm to the side of the COM; the planar models take 0");
  if (asym > 1e-3) r.notes.push_back("left and right foot spacings differ by " + g6(1e3 * asym) + " mm; l_F_m is their mean");
  if (r.foot_count == 3) r.notes.push_back(threeFeetNote(r));
  r.notes.push_back("tilt after standing: " + g6(r.tilt_deg) + " deg");
  if (!messages.text().empty()) r.notes.push_back(messages.text());
  settledJoints(m, d, stance, hold, r);
  return r;
}

std::string threeFeetNote(const DerivedRobot& r) {
  std::string names;
  for (const std::string& f : r.feet) names += (names.empty() ? "" : ", ") + f;
  return "the robot stands on 3 feet (" + names +
         "): only the articulated MuJoCo model runs on it; the planar models (analytic, perfoot) and MuJoCo's rigid "
         "box take a body on 4 feet at a rectangle's corners (its derived l_F_m and w_F_m are the support "
         "triangle's extents, not their input)";
}

std::string describeDerivedRobot(const DerivedRobot& r) {
  std::ostringstream o;
  o << "robot: " << r.model.source << (r.model.from_urdf ? " (URDF)" : "") << "\n";
  o << "stance: " << r.stance << "\n";
  o << (r.foot_count == 4 ? "feet (FL, FR, RR, RL): " : "feet (front to back): ");
  for (std::size_t i = 0; i < r.feet.size(); ++i) o << (i ? ", " : "") << r.feet[i];
  o << "\n\n";
  std::size_t w = 0;
  for (const DerivedValue& v : r.values) w = std::max(w, v.key.size());
  for (const DerivedValue& v : r.values) {
    char line[160];
    std::snprintf(line, sizeof line, "%-*s  %-14.9g %-7s ", static_cast<int>(w), v.key.c_str(), v.value, v.unit.c_str());
    o << line << v.source << "\n";
  }
  o << "\n";
  for (const std::string& n : r.model.notes) o << "note: " << n << "\n";
  for (const std::string& n : r.notes) o << "note: " << n << "\n";
  return o.str();
}

}  // namespace tailsim
