// The peer of `fitup import` (docs/performance.md, "STEP import"): Open CASCADE's own
// C++ reader alone on the same file — STEPCAFControl_Reader::ReadFile and Transfer
// into an XCAF document with the length unit in mm, then BRepMesh_IncrementalMesh of
// every solid with the same deflection and angle — timed by steady_clock, with the
// process's peak resident memory (VmHWM). No fitup code. Built by tests/bench/step.sh:
//   g++ -O2 -std=c++17 -I/usr/include/opencascade occt_peer.cpp -lTKXDESTEP … -o occt_peer
// Usage: occt_peer FILE.step [DEFLECTION_MM [ANGLE_RAD]]
#include <BRepMesh_IncrementalMesh.hxx>
#include <IMeshTools_Parameters.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Poly_Triangulation.hxx>
#include <BRep_Tool.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <string>

static double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

static long peak_kb() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      return std::atol(line.c_str() + 6);
    }
  }
  return 0;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: occt_peer FILE.step [DEFLECTION_MM [ANGLE_RAD]]\n");
    return 2;
  }
  const double deflection = argc > 2 ? std::atof(argv[2]) : 0.1;
  const double angle = argc > 3 ? std::atof(argv[3]) : 0.5;
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
  const auto start = std::chrono::steady_clock::now();
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  STEPCAFControl_Reader reader;
  reader.SetNameMode(Standard_True);
  reader.SetColorMode(Standard_False);
  reader.SetLayerMode(Standard_False);
  if (reader.ReadFile(argv[1]) != IFSelect_RetDone) {
    std::fprintf(stderr, "cannot parse %s\n", argv[1]);
    return 1;
  }
  const double parse = since(start);
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  XCAFDoc_DocumentTool::SetLengthUnit(doc, 1.0, UnitsMethods_LengthUnit_Millimeter);
  auto t1 = std::chrono::steady_clock::now();
  if (!reader.Transfer(doc)) {
    std::fprintf(stderr, "cannot transfer %s\n", argv[1]);
    return 1;
  }
  const double transfer = since(t1);
  // Mesh each distinct solid once (as fitup does), unplaced.
  t1 = std::chrono::steady_clock::now();
  Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  TDF_LabelSequence shapes;
  tool->GetShapes(shapes);
  std::set<const void *> seen;
  long triangles = 0;
  int solids = 0;
  for (Standard_Integer i = 1; i <= shapes.Length(); ++i) {
    if (!XCAFDoc_ShapeTool::IsSimpleShape(shapes.Value(i))) {
      continue;
    }
    const TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(shapes.Value(i));
    for (TopExp_Explorer sx(shape, TopAbs_SOLID); sx.More(); sx.Next()) {
      if (!seen.insert(sx.Current().TShape().get()).second) {
        continue;
      }
      ++solids;
      const TopoDS_Shape solid = sx.Current().Located(TopLoc_Location());
      IMeshTools_Parameters params;
      params.Deflection = deflection;
      params.Angle = angle;
      params.InParallel = Standard_False;
      BRepMesh_IncrementalMesh mesher(solid, params);
      for (TopExp_Explorer fx(solid, TopAbs_FACE); fx.More(); fx.Next()) {
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) &t = BRep_Tool::Triangulation(TopoDS::Face(fx.Current()), loc);
        if (!t.IsNull()) {
          triangles += t->NbTriangles();
        }
      }
    }
  }
  const double mesh = since(t1);
  std::printf("parse %.3f transfer %.3f mesh %.3f total %.3f s; %d solids, %ld triangles; peak %ld kB\n",
              parse, transfer, mesh, since(start), solids, triangles, peak_kb());
  app->Close(doc);
  return 0;
}
