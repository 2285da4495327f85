// Which solids of a STEP file Open CASCADE itself reads as closed and valid: the
// corpus's admission rule (docs/document.md, "Real CAD exports"; issue 38: "every file
// Open CASCADE reads as closed solids imports"). Open CASCADE alone — no fitup code —
// reads the file into an XCAF document, walks the assembly tree (to report its depth:
// 1 = a flat assembly, 2+ = nested sub-assemblies) and checks every distinct solid:
// BRepCheck_Analyzer's validity, and its free edges (an edge of a single face, neither
// degenerated nor a seam), which a closed solid has none of.
//   g++ -O2 -std=c++17 -I/usr/include/opencascade occt_closed.cpp -lTKXDESTEP … -o occt_closed
// Usage: occt_closed FILE.step
// Output (one tab-separated line):
//   FILE  solids <distinct>  placed <placed>  valid <n>  closed <n>  depth <d>  loose <shells/faces outside solids>
#include <BRepCheck_Analyzer.hxx>
#include <BRep_Tool.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListIteratorOfListOfShape.hxx>
#include <TopTools_MapOfShape.hxx>
#include <TopoDS.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>

#include <cstdio>

static int placed = 0, depth_max = 0;
static TopTools_MapOfShape distinct;

static void walk(const TDF_Label &label, int depth) {
  if (depth > 64) {
    return;
  }
  if (XCAFDoc_ShapeTool::IsAssembly(label)) {
    if (depth + 1 > depth_max) {
      depth_max = depth + 1;
    }
    TDF_LabelSequence comps;
    XCAFDoc_ShapeTool::GetComponents(label, comps, Standard_False);
    for (Standard_Integer i = 1; i <= comps.Length(); ++i) {
      TDF_Label referred;
      if (XCAFDoc_ShapeTool::GetReferredShape(comps.Value(i), referred)) {
        walk(referred, depth + 1);
      }
    }
    return;
  }
  const TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
  for (TopExp_Explorer sx(shape, TopAbs_SOLID); sx.More(); sx.Next()) {
    ++placed;
    distinct.Add(sx.Current().Located(TopLoc_Location()));
  }
}

// Free edges of a solid: bound to one face only, not degenerated, not a seam.
static int free_edges(const TopoDS_Shape &solid) {
  TopTools_IndexedDataMapOfShapeListOfShape map;
  TopExp::MapShapesAndAncestors(solid, TopAbs_EDGE, TopAbs_FACE, map);
  int n = 0;
  for (Standard_Integer i = 1; i <= map.Extent(); ++i) {
    const TopoDS_Edge &e = TopoDS::Edge(map.FindKey(i));
    if (BRep_Tool::Degenerated(e)) {
      continue;
    }
    const TopTools_ListOfShape &faces = map.FindFromIndex(i);
    if (faces.Extent() == 1 && !BRep_Tool::IsClosed(e, TopoDS::Face(faces.First()))) {
      ++n;
    }
  }
  return n;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: occt_closed FILE.step\n");
    return 2;
  }
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  STEPCAFControl_Reader reader;
  if (reader.ReadFile(argv[1]) != IFSelect_RetDone) {
    std::fprintf(stderr, "cannot parse %s\n", argv[1]);
    return 1;
  }
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  if (!reader.Transfer(doc)) {
    std::fprintf(stderr, "cannot transfer %s\n", argv[1]);
    return 1;
  }
  Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  TDF_LabelSequence roots;
  tool->GetFreeShapes(roots);
  int loose = 0;
  for (Standard_Integer i = 1; i <= roots.Length(); ++i) {
    walk(roots.Value(i), 0);
    const TopoDS_Shape s = XCAFDoc_ShapeTool::GetShape(roots.Value(i));
    for (TopExp_Explorer x(s, TopAbs_SHELL, TopAbs_SOLID); x.More(); x.Next()) {
      ++loose;
    }
    for (TopExp_Explorer x(s, TopAbs_FACE, TopAbs_SHELL); x.More(); x.Next()) {
      ++loose;
    }
  }
  int valid = 0, closed = 0;
  for (TopTools_MapOfShape::Iterator it(distinct); it.More(); it.Next()) {
    if (BRepCheck_Analyzer(it.Value()).IsValid()) {
      ++valid;
    }
    if (free_edges(it.Value()) == 0) {
      ++closed;
    }
  }
  std::printf("%s\tsolids %d\tplaced %d\tvalid %d\tclosed %d\tdepth %d\tloose %d\n", argv[1],
              distinct.Extent(), placed, valid, closed, depth_max, loose);
  app->Close(doc);
  return 0;
}
