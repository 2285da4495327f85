// fitup's STEP shim (feature `step`): the only C++ in fitup. It keeps to what Rust
// cannot do without Open CASCADE — reading, transferring and meshing B-reps — and
// returns plain data; every check and every decision is made in src/mesh/step.rs.
// Built by build.rs with cxx-build against Debian's OCCT 7.6 headers.
#include "fitup/cpp/step_shim.h"
#include "fitup/src/mesh/step_ffi.rs.h"

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <IMeshTools_Parameters.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Message_ProgressIndicator.hxx>
#include <Poly_Triangulation.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>
#include <Standard_OutOfMemory.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Ax2.hxx>
#include <gp_Pln.hxx>
#include <gp_Ax3.hxx>
#include <Geom_Plane.hxx>
#include <TopTools_ListOfShape.hxx>
#include <gp_Trsf.hxx>

#include <chrono>
#include <map>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>

namespace fitup_step {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// OCCT's progress indicator is its only cancellation hook: transfer and meshing
// poll UserBreak(), which turns the caller's time limit into a clean stop.
class Deadline : public Message_ProgressIndicator {
public:
  explicit Deadline(Clock::time_point end) : end_(end) {}
  Standard_Boolean UserBreak() override { return Clock::now() > end_; }
  void Show(const Message_ProgressScope &, const Standard_Boolean) override {}

private:
  Clock::time_point end_;
};

// OCCT prints warnings and statistics on standard output by default; fitup's
// output is its own, so the printers go (once per process).
void quiet() {
  static std::once_flag once;
  std::call_once(once, [] {
    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
  });
}

std::string utf8(const TCollection_ExtendedString &e) {
  std::string out(static_cast<size_t>(e.LengthOfCString()) + 1, '\0');
  Standard_PCharacter p = &out[0];
  const Standard_Integer n = e.ToUTF8CString(p);
  out.resize(n > 0 ? static_cast<size_t>(n) : 0);
  return out;
}

std::string label_name(const TDF_Label &l) {
  Handle(TDataStd_Name) n;
  if (l.IsNull() || !l.FindAttribute(TDataStd_Name::GetID(), n)) {
    return {};
  }
  return utf8(n->Get());
}

rust::String lossy(const std::string &s) { return rust::String::lossy(s.data(), s.size()); }

Failure failure(Cause cause) {
  Failure f{};
  f.cause = cause;
  f.stage = Stage::Reading;
  return f;
}

// A stop the shim decides itself (the time limit, the triangle cap, the depth, the
// test writer's refusals): thrown, and caught by `guarded`, which hands it to Rust.
struct Stopped {
  Failure failure;
};

[[noreturn]] void stop(Cause cause) { throw Stopped{failure(cause)}; }

// The test writer's own refusal (an Exception of class `write`).
[[noreturn]] void refuse_write(const std::string &message) {
  Failure f = failure(Cause::Exception);
  f.kind = "write";
  f.message = lossy(message);
  throw Stopped{std::move(f)};
}

struct Walker {
  Handle(XCAFDoc_ShapeTool) tool;
  ReadOptions options;
  Clock::time_point end;
  Model &model;
  std::map<const void *, uint32_t> parts; // TShape → index in model.parts
  uint64_t triangles = 0;
  double mesh_s = 0;

  void check_time(Stage stage) const {
    if (Clock::now() > end) {
      Failure f = failure(Cause::TimeLimit);
      f.stage = stage;
      throw Stopped{std::move(f)};
    }
  }

  // Meshes the solid (unplaced, its own frame) once per `key` (its TShape, or the
  // shell's it was made of); returns its part index.
  uint32_t part_of(const TopoDS_Shape &placed, const void *key, const std::string &product,
                   uint32_t solid_index, uint32_t solids) {
    auto found = parts.find(key);
    if (found != parts.end()) {
      return found->second;
    }
    check_time(Stage::Meshing);
    TopoDS_Shape solid = placed.Located(TopLoc_Location());
    SolidPart part;
    part.name = lossy(product);
    part.solid_index = solid_index;
    part.solids_in_product = solids;
    GProp_GProps props;
    BRepGProp::VolumeProperties(solid, props);
    part.exact_volume = props.Mass();
    if (part.exact_volume < 0) {
      // An inside-out solid (a shell oriented inwards): turned, so normals point out.
      solid.Reverse();
      part.exact_volume = -part.exact_volume;
    }
    const Clock::time_point t0 = Clock::now();
    IMeshTools_Parameters params;
    params.Deflection = options.linear_deflection;
    params.Angle = options.angular_deflection;
    params.InParallel = Standard_False;
    Handle(Deadline) progress = new Deadline(end);
    BRepMesh_IncrementalMesh mesher(solid, params, progress->Start());
    mesh_s += seconds_since(t0);
    check_time(Stage::Meshing);
    part.faces = 0;
    part.unmeshed_faces = 0;
    part.first_unmeshed_face = 0;
    for (TopExp_Explorer fx(solid, TopAbs_FACE); fx.More(); fx.Next()) {
      const TopoDS_Face &face = TopoDS::Face(fx.Current());
      part.faces += 1;
      TopLoc_Location loc;
      const Handle(Poly_Triangulation) &tri = BRep_Tool::Triangulation(face, loc);
      if (tri.IsNull() || tri->NbTriangles() == 0) {
        if (part.unmeshed_faces == 0) {
          part.first_unmeshed_face = part.faces;
        }
        part.unmeshed_faces += 1;
        continue;
      }
      triangles += static_cast<uint64_t>(tri->NbTriangles());
      if (triangles > options.max_triangles) {
        stop(Cause::TooManyTriangles);
      }
      const gp_Trsf tr = loc.Transformation();
      const uint32_t base = static_cast<uint32_t>(part.vertices.size() / 3);
      for (Standard_Integer i = 1; i <= tri->NbNodes(); ++i) {
        const gp_Pnt p = tri->Node(i).Transformed(tr);
        part.vertices.push_back(p.X());
        part.vertices.push_back(p.Y());
        part.vertices.push_back(p.Z());
      }
      // A reversed face's triangles wind the other way round its outward normal.
      const bool reversed = face.Orientation() == TopAbs_REVERSED;
      for (Standard_Integer i = 1; i <= tri->NbTriangles(); ++i) {
        Standard_Integer a, b, c;
        tri->Triangle(i).Get(a, b, c);
        if (reversed) {
          std::swap(b, c);
        }
        part.triangles.push_back(base + static_cast<uint32_t>(a - 1));
        part.triangles.push_back(base + static_cast<uint32_t>(b - 1));
        part.triangles.push_back(base + static_cast<uint32_t>(c - 1));
      }
    }
    const uint32_t index = static_cast<uint32_t>(model.parts.size());
    model.parts.push_back(std::move(part));
    parts.emplace(key, index);
    return index;
  }

  // Rotation and translation (mm) of `t`, row-major 3 × 4.
  static void put_matrix(const gp_Trsf &t, rust::Vec<double> &out) {
    const gp_Mat r = t.HVectorialPart();
    const gp_XYZ x = t.TranslationPart();
    for (int row = 1; row <= 3; ++row) {
      for (int col = 1; col <= 3; ++col) {
        out.push_back(r.Value(row, col));
      }
      out.push_back(x.Coord(row));
    }
  }

  void add_instance(const TopoDS_Shape &solid, const gp_Trsf &placement, uint32_t part,
                    const std::string &name, const std::string &path, uint32_t parent) {
    const gp_Trsf t = placement * solid.Location().Transformation();
    Instance inst;
    inst.name = lossy(name);
    inst.path = lossy(path);
    inst.part = part;
    inst.parent = parent;
    put_matrix(t, inst.matrix);
    inst.scale = t.ScaleFactor();
    model.instances.push_back(std::move(inst));
  }

  // A product (simple shape label): its solids become parts, placed at `placement`.
  void product(const TDF_Label &label, const gp_Trsf &placement, const std::string &instance,
               const std::string &path, uint32_t parent) {
    const TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
    std::string name = label_name(label);
    uint32_t solids = 0;
    for (TopExp_Explorer sx(shape, TopAbs_SOLID); sx.More(); sx.Next()) {
      ++solids;
    }
    for (TopExp_Explorer fx(shape, TopAbs_FACE, TopAbs_SHELL); fx.More(); fx.Next()) {
      model.faces_without_solid += 1;
    }
    uint32_t i = 0;
    for (TopExp_Explorer sx(shape, TopAbs_SOLID); sx.More(); sx.Next()) {
      ++i;
      const uint32_t part = part_of(sx.Current(), sx.Current().TShape().get(), name, i, solids);
      add_instance(sx.Current(), placement, part, instance, path, parent);
    }
    // Shells outside any solid: a closed one (some exporters write solids as surface
    // models) is taken as the solid it bounds; an open one is reported.
    for (TopExp_Explorer sx(shape, TopAbs_SHELL, TopAbs_SOLID); sx.More(); sx.Next()) {
      model.shells_without_solid += 1;
      const TopoDS_Shape &shell = sx.Current();
      if (!BRep_Tool::IsClosed(shell)) {
        if (model.open_shells == 0) {
          model.first_open_shell = lossy(path.empty() ? name : path);
        }
        model.open_shells += 1;
        continue;
      }
      BRep_Builder b;
      TopoDS_Solid solid;
      b.MakeSolid(solid);
      b.Add(solid, shell.Located(TopLoc_Location()));
      const TopoDS_Shape placed = solid.Located(shell.Location());
      ++i;
      const uint32_t part = part_of(placed, shell.TShape().get(), name, i, solids);
      add_instance(placed, placement, part, instance, path, parent);
    }
  }

  // `parent`: the assembly occurrence holding this one (1-based index into
  // model.assemblies; 0 at the top).
  void walk(const TDF_Label &label, const gp_Trsf &placement, const std::string &instance,
            const std::string &path, int depth, uint32_t parent) {
    if (depth > 64) {
      Failure f = failure(Cause::TooDeep);
      f.at = lossy(path);
      throw Stopped{std::move(f)};
    }
    if (XCAFDoc_ShapeTool::IsAssembly(label)) {
      // The occurrence itself, before what it holds (parents before children).
      Assembly a;
      a.name = lossy(instance);
      a.path = lossy(path);
      a.product = lossy(label_name(label));
      a.parent = parent;
      put_matrix(placement, a.matrix);
      a.scale = placement.ScaleFactor();
      model.assemblies.push_back(std::move(a));
      const uint32_t self = static_cast<uint32_t>(model.assemblies.size());
      TDF_LabelSequence components;
      XCAFDoc_ShapeTool::GetComponents(label, components, Standard_False);
      for (Standard_Integer i = 1; i <= components.Length(); ++i) {
        const TDF_Label &c = components.Value(i);
        TDF_Label referred;
        if (!XCAFDoc_ShapeTool::GetReferredShape(c, referred)) {
          continue;
        }
        const gp_Trsf here = placement * XCAFDoc_ShapeTool::GetLocation(c).Transformation();
        std::string name = label_name(c);
        if (name.empty()) {
          name = label_name(referred);
        }
        walk(referred, here, name, path + "/" + name, depth + 1, self);
      }
    } else if (XCAFDoc_ShapeTool::IsSimpleShape(label)) {
      product(label, placement, instance, path, parent);
    }
  }
};

void read_units(STEPControl_Reader &reader, Model &model) {
  TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
  reader.FileUnits(lengths, angles, solid_angles);
  if (lengths.Length() > 0) {
    model.length_unit = lossy(lengths.Value(1).ToCString());
  }
}

Model read(rust::Str path, const ReadOptions &options) {
  quiet();
  const Clock::time_point start = Clock::now();
  const Clock::time_point end =
      start + std::chrono::duration_cast<Clock::duration>(
                  std::chrono::duration<double>(options.time_limit_s));
  // Lengths come out in mm whatever unit the file uses: OCCT scales to the
  // session's unit and to the XCAF document's unit, both set to mm here.
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  Model model;
  model.shells_without_solid = 0;
  model.faces_without_solid = 0;
  model.open_shells = 0;
  STEPCAFControl_Reader reader;
  reader.SetNameMode(Standard_True);
  reader.SetColorMode(Standard_False);
  reader.SetLayerMode(Standard_False);
  const std::string file(path.data(), path.size());
  if (reader.ReadFile(file.c_str()) != IFSelect_RetDone) {
    stop(Cause::Parse);
  }
  model.read_s = seconds_since(start);
  read_units(reader.ChangeReader(), model);
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  XCAFDoc_DocumentTool::SetLengthUnit(doc, 1.0, UnitsMethods_LengthUnit_Millimeter);
  const Clock::time_point t1 = Clock::now();
  Handle(Deadline) progress = new Deadline(end);
  const bool ok = reader.Transfer(doc, progress->Start());
  model.transfer_s = seconds_since(t1);
  Walker w{XCAFDoc_DocumentTool::ShapeTool(doc->Main()), options, end, model, {}, 0, 0};
  w.check_time(Stage::Transferring);
  if (!ok) {
    app->Close(doc);
    stop(Cause::Transfer);
  }
  TDF_LabelSequence roots;
  w.tool->GetFreeShapes(roots);
  for (Standard_Integer i = 1; i <= roots.Length(); ++i) {
    const TDF_Label &root = roots.Value(i);
    std::string name = label_name(root);
    const gp_Trsf placement = XCAFDoc_ShapeTool::GetLocation(root).Transformation();
    w.walk(root, placement, name, name, 0, 0);
  }
  model.mesh_s = w.mesh_s;
  app->Close(doc);
  return model;
}

// ---- test files, made with OCCT itself -------------------------------------------

TDF_Label named(const Handle(XCAFDoc_ShapeTool) &tool, const TopoDS_Shape &s, const char *name) {
  TDF_Label l = tool->AddShape(s, Standard_False);
  TDataStd_Name::Set(l, name);
  return l;
}

// A turn of `deg` degrees about the axis (ax, ay, az) through the origin, then a
// shift by (x, y, z) mm.
TopLoc_Location pose(double ax, double ay, double az, double deg, double x, double y,
                     double z) {
  gp_Trsf t;
  t.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(ax, ay, az)), deg * M_PI / 180.0);
  t.SetTranslationPart(gp_Vec(x, y, z));
  return TopLoc_Location(t);
}

TopLoc_Location at(double x, double y, double z) {
  gp_Trsf t;
  t.SetTranslation(gp_Vec(x, y, z));
  return TopLoc_Location(t);
}

// A solid bounded by a 10 mm cube's first five faces and whatever `top(builder, shell,
// face)` adds to its shell for the sixth (BRepPrim's face order: x-, x+, y-, y+, z-,
// z+; adding nothing leaves the top open).
template <class Top> TopoDS_Solid cube_with_top(Top top) {
  const TopoDS_Shape cube = BRepPrimAPI_MakeBox(10.0, 10.0, 10.0).Shape();
  BRep_Builder b;
  TopoDS_Shell shell;
  b.MakeShell(shell);
  int n = 0;
  for (TopExp_Explorer fx(cube, TopAbs_FACE); fx.More(); fx.Next()) {
    if (++n < 6) {
      b.Add(shell, fx.Current());
    } else {
      top(b, shell, TopoDS::Face(fx.Current()));
    }
  }
  TopoDS_Solid solid;
  b.MakeSolid(solid);
  b.Add(solid, shell);
  return solid;
}

void write_doc(const Handle(TDocStd_Document) &doc, const std::string &file) {
  STEPCAFControl_Writer writer;
  writer.SetNameMode(Standard_True);
  if (!writer.Transfer(doc, STEPControl_AsIs) || writer.Write(file.c_str()) != IFSelect_RetDone) {
    refuse_write("cannot write " + file);
  }
}

void write_shape(const TopoDS_Shape &s, const std::string &file) {
  STEPControl_Writer writer;
  if (writer.Transfer(s, STEPControl_AsIs) != IFSelect_RetDone ||
      writer.Write(file.c_str()) != IFSelect_RetDone) {
    refuse_write("cannot write " + file);
  }
}

void write_test(const std::string &kind, const std::string &file) {
  quiet();
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  Interface_Static::SetCVal("write.step.unit", "MM");
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  XCAFDoc_DocumentTool::SetLengthUnit(doc, 1.0, UnitsMethods_LengthUnit_Millimeter);
  Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  if (kind == "box") {
    named(tool, BRepPrimAPI_MakeBox(20.0, 10.0, 5.0).Shape(), "block");
    write_doc(doc, file);
  } else if (kind == "cylinder_hole") {
    // r 10 mm, 20 mm high, a 3 mm hole along its axis (taller than the cylinder, so
    // the cut has no coplanar faces).
    TopoDS_Shape body = BRepPrimAPI_MakeCylinder(10.0, 20.0).Shape();
    TopoDS_Shape hole =
        BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -1), gp::DZ()), 3.0, 22.0).Shape();
    BRepAlgoAPI_Cut cut(body, hole);
    if (!cut.IsDone()) {
      refuse_write("the boolean cut failed");
    }
    named(tool, cut.Shape(), "bushing");
    write_doc(doc, file);
  } else if (kind == "assembly") {
    // cell: plate-1 at the origin, a sub-assembly `pegs` (two pegs standing on the
    // plate) placed 10 mm up, and a third peg lying on the plate (90° about X).
    TDF_Label plate = named(tool, BRepPrimAPI_MakeBox(100.0, 60.0, 10.0).Shape(), "plate");
    TDF_Label peg = named(tool, BRepPrimAPI_MakeCylinder(4.0, 30.0).Shape(), "peg");
    TDF_Label pegs = tool->NewShape();
    TDataStd_Name::Set(pegs, "pegs");
    TDataStd_Name::Set(tool->AddComponent(pegs, peg, at(20, 30, 0)), "peg-1");
    TDataStd_Name::Set(tool->AddComponent(pegs, peg, at(80, 30, 0)), "peg-2");
    TDF_Label cell = tool->NewShape();
    TDataStd_Name::Set(cell, "cell");
    TDataStd_Name::Set(tool->AddComponent(cell, plate, TopLoc_Location()), "plate-1");
    TDataStd_Name::Set(tool->AddComponent(cell, pegs, at(0, 0, 10)), "pegs-1");
    gp_Trsf lying;
    lying.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp::DX()), M_PI / 2);
    lying.SetTranslationPart(gp_Vec(50, 45, 14));
    TDataStd_Name::Set(tool->AddComponent(cell, peg, TopLoc_Location(lying)), "peg-3");
    tool->UpdateAssemblies();
    write_doc(doc, file);
  } else if (kind == "nested") {
    // Three levels of sub-assemblies, placed with rotations, one product used in two
    // places, and two occurrences named as SolidWorks names them (`NAUO<n>`):
    //   cart ─ Frame-1, Frame-2 (frame) ─ plate-1, Axle-1, Axle-2 (axle_asm) ─ bar-1,
    //   Wheel-1, Wheel-2;  cart ─ NAUO7 (a wheel), NAUO8 (an axle_asm).
    // tests/it/step_import.rs (nested_assemblies) repeats these placements.
    TDF_Label wheel = named(tool, BRepPrimAPI_MakeCylinder(10.0, 5.0).Shape(), "wheel");
    TDF_Label bar = named(tool, BRepPrimAPI_MakeBox(4.0, 4.0, 60.0).Shape(), "axle_bar");
    TDF_Label plate = named(tool, BRepPrimAPI_MakeBox(100.0, 60.0, 5.0).Shape(), "frame_plate");
    TDF_Label axle = tool->NewShape();
    TDataStd_Name::Set(axle, "axle_asm");
    TDataStd_Name::Set(tool->AddComponent(axle, bar, TopLoc_Location()), "bar-1");
    TDataStd_Name::Set(tool->AddComponent(axle, wheel, pose(1, 0, 0, 180, 2, 2, 0)), "Wheel-1");
    TDataStd_Name::Set(tool->AddComponent(axle, wheel, pose(0, 0, 1, 30, 2, 2, 60)), "Wheel-2");
    TDF_Label frame = tool->NewShape();
    TDataStd_Name::Set(frame, "frame");
    TDataStd_Name::Set(tool->AddComponent(frame, plate, TopLoc_Location()), "plate-1");
    TDataStd_Name::Set(tool->AddComponent(frame, axle, pose(0, 1, 0, 90, 10, 0, 5)), "Axle-1");
    TDataStd_Name::Set(tool->AddComponent(frame, axle, pose(1, 1, 0, -60, 90, 0, 5)), "Axle-2");
    TDF_Label cart = tool->NewShape();
    TDataStd_Name::Set(cart, "cart");
    TDataStd_Name::Set(tool->AddComponent(cart, frame, pose(0, 0, 1, 45, 0, 0, 20)), "Frame-1");
    TDataStd_Name::Set(tool->AddComponent(cart, frame, pose(1, 0, 0, 180, 200, 0, 0)), "Frame-2");
    TDataStd_Name::Set(tool->AddComponent(cart, wheel, pose(0, 1, 0, 90, -50, 0, 0)), "NAUO7");
    TDataStd_Name::Set(tool->AddComponent(cart, axle, pose(0, 0, 1, -90, 0, -80, 0)), "NAUO8");
    tool->UpdateAssemblies();
    write_doc(doc, file);
  } else if (kind == "roots") {
    // Several free shapes, as some exporters write them: two root assemblies with one
    // product name (`module`), each holding a block and a sub-assembly `pair` of two
    // pegs at other placements, and a loose solid that is in no assembly.
    // tests/it/step_import.rs (several_roots) repeats these placements.
    TDF_Label peg = named(tool, BRepPrimAPI_MakeCylinder(4.0, 30.0).Shape(), "peg");
    TDF_Label block = named(tool, BRepPrimAPI_MakeBox(10.0, 20.0, 5.0).Shape(), "block");
    TDF_Label pair = tool->NewShape();
    TDataStd_Name::Set(pair, "pair");
    TDataStd_Name::Set(tool->AddComponent(pair, peg, TopLoc_Location()), "peg-1");
    TDataStd_Name::Set(tool->AddComponent(pair, peg, pose(1, 0, 0, 90, 20, 0, 4)), "peg-2");
    TDF_Label first = tool->NewShape();
    TDataStd_Name::Set(first, "module");
    TDataStd_Name::Set(tool->AddComponent(first, block, TopLoc_Location()), "block-1");
    TDataStd_Name::Set(tool->AddComponent(first, pair, pose(0, 0, 1, 30, 40, 10, 5)), "pair-1");
    TDF_Label second = tool->NewShape();
    TDataStd_Name::Set(second, "module");
    TDataStd_Name::Set(tool->AddComponent(second, pair, pose(0, 1, 0, -45, 100, 50, 0)), "pair-1");
    TDataStd_Name::Set(tool->AddComponent(second, block, pose(1, 1, 1, 120, 150, 0, 0)), "block-1");
    named(tool, BRepPrimAPI_MakeBox(gp_Pnt(300, 0, 0), 3.0, 3.0, 3.0).Shape(), "loose");
    tool->UpdateAssemblies();
    write_doc(doc, file);
  } else if (kind == "inch_box") {
    // 1 × 2 × 3 in, written in inches (the file's numbers are 1, 2, 3).
    Interface_Static::SetCVal("write.step.unit", "INCH");
    named(tool, BRepPrimAPI_MakeBox(25.4, 50.8, 76.2).Shape(), "inch_block");
    write_doc(doc, file);
    Interface_Static::SetCVal("write.step.unit", "MM");
  } else if (kind == "open_shell") {
    // A "solid" bounded by five faces of a cube: its top is missing.
    const TopoDS_Solid solid =
        cube_with_top([](BRep_Builder &, TopoDS_Shell &, const TopoDS_Face &) {});
    // In an assembly beside a sound block, so the error must name which one.
    TDF_Label lidless = named(tool, solid, "lidless");
    TDF_Label block = named(tool, BRepPrimAPI_MakeBox(10.0, 10.0, 10.0).Shape(), "block");
    TDF_Label cell = tool->NewShape();
    TDataStd_Name::Set(cell, "cell");
    TDataStd_Name::Set(tool->AddComponent(cell, block, TopLoc_Location()), "block-1");
    TDataStd_Name::Set(tool->AddComponent(cell, lidless, at(20, 0, 0)), "lidless-1");
    tool->UpdateAssemblies();
    write_doc(doc, file);
  } else if (kind == "bad_face") {
    // A cube whose top face is put on the plane x = 0, at right angles to its own
    // edges: read back, its boundary projects onto that plane as a loop without area,
    // which BRepMesh cannot fill (a face that does not mesh).
    const TopoDS_Solid solid =
        cube_with_top([](BRep_Builder &b, TopoDS_Shell &shell, const TopoDS_Face &top) {
          TopoDS_Face bad;
          b.MakeFace(bad, new Geom_Plane(gp_Ax3(gp_Pnt(0, 0, 0), gp::DX())), 1e-7);
          for (TopExp_Explorer wx(top, TopAbs_WIRE); wx.More(); wx.Next()) {
            b.Add(bad, wx.Current());
          }
          bad.Orientation(top.Orientation());
          b.Add(shell, bad);
        });
    named(tool, solid, "warped");
    write_doc(doc, file);
  } else if (kind == "plate_holes") {
    // A 200 × 200 × 10 mm plate with 12 × 12 holes of r 4 mm (the larger file the
    // performance notes time).
    TopoDS_Shape plate = BRepPrimAPI_MakeBox(200.0, 200.0, 10.0).Shape();
    TopTools_ListOfShape tools;
    for (int i = 0; i < 12; ++i) {
      for (int j = 0; j < 12; ++j) {
        tools.Append(BRepPrimAPI_MakeCylinder(
                         gp_Ax2(gp_Pnt(12.0 + 16.0 * i, 12.0 + 16.0 * j, -1.0), gp::DZ()), 4.0,
                         12.0)
                         .Shape());
      }
    }
    TopTools_ListOfShape args;
    args.Append(plate);
    BRepAlgoAPI_Cut cut;
    cut.SetArguments(args);
    cut.SetTools(tools);
    cut.Build();
    if (!cut.IsDone()) {
      refuse_write("the boolean cut failed");
    }
    named(tool, cut.Shape(), "perforated");
    write_doc(doc, file);
  } else if (kind == "sphere") {
    // r 10 mm: Open CASCADE meshes its poles with several nodes at one point.
    named(tool, BRepPrimAPI_MakeSphere(10.0).Shape(), "ball");
    write_doc(doc, file);
  } else if (kind == "cone") {
    // r 8 mm at the base, 15 mm high, to an apex.
    named(tool, BRepPrimAPI_MakeCone(8.0, 0.0, 15.0).Shape(), "tip");
    write_doc(doc, file);
  } else if (kind == "no_solid") {
    write_shape(BRepBuilderAPI_MakeFace(gp_Pln(), 0.0, 10.0, 0.0, 10.0).Shape(), file);
  } else {
    app->Close(doc);
    refuse_write("unknown test file kind " + kind);
  }
  app->Close(doc);
}

Failure exception(const std::string &cls, const char *message) {
  Failure f = failure(Cause::Exception);
  f.kind = lossy(cls);
  f.message = lossy(message ? message : "");
  return f;
}

// Runs `f` and says how it stopped: every failure (the shim's own stops, OCCT's
// exceptions, which do not derive from std::exception, an allocation failure) is a
// Failure handed to Rust as data, never an exception across the boundary.
template <class F> Failure guarded(F f) {
  try {
    f();
    return failure(Cause::Done);
  } catch (const Stopped &s) {
    return s.failure;
  } catch (const Standard_Failure &e) {
    if (e.IsKind(STANDARD_TYPE(Standard_OutOfMemory))) {
      return failure(Cause::OutOfMemory);
    }
    return exception(e.DynamicType()->Name(), e.GetMessageString());
  } catch (const std::bad_alloc &) {
    return failure(Cause::OutOfMemory);
  } catch (const std::exception &e) {
    return exception("std::exception", e.what());
  } catch (...) {
    return exception("unknown C++ exception", "");
  }
}

} // namespace

Answer read_step(rust::Str path, const ReadOptions &options) {
  Answer answer{};
  answer.failure = guarded([&] { answer.model = read(path, options); });
  return answer;
}

Failure write_test_step(rust::Str kind, rust::Str path) {
  return guarded([&] {
    write_test(std::string(kind.data(), kind.size()), std::string(path.data(), path.size()));
  });
}

} // namespace fitup_step
