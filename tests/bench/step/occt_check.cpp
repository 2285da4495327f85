// An independent reference for `fitup import` on real CAD files (docs/performance.md,
// "STEP import: real CAD exports"; tests/it/step_corpus.rs): Open CASCADE alone — no
// fitup code — reads the file with STEPCAFControl_Reader into an XCAF document in mm,
// walks the assembly tree from its free shapes composing every component's location,
// and prints one line per placed solid with its product's name, its exact B-rep volume
// (BRepGProp, mm³, of the unplaced solid) and its placement part → root as a 3 × 4
// row-major [R | t] (mm, column vectors). Built by tests/bench/step_corpus.sh:
//   g++ -O2 -std=c++17 -I/usr/include/opencascade occt_check.cpp -lTKXDESTEP … -o occt_check
// Usage: occt_check FILE.step
// Output (tab-separated):
//   unit    <the file's first length unit, as Open CASCADE names it>
//   solid   <instance path>  <product name>  <volume mm³>  <r00 r01 r02 t0 r10 … t2>
//   assembly <instance path>  <product name>  <r00 r01 r02 t0 r10 … t2>
// (an `assembly` line for the root and every sub-assembly occurrence, before the lines
// of what it holds; its placement is the assembly frame → root).
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>

#include <cstdio>
#include <string>

static std::string name_of(const TDF_Label &l) {
  Handle(TDataStd_Name) n;
  if (!l.FindAttribute(TDataStd_Name::GetID(), n)) {
    return "";
  }
  const TCollection_ExtendedString &e = n->Get();
  char *buf = new char[e.LengthOfCString() + 1];
  e.ToUTF8CString(buf);
  std::string s(buf);
  delete[] buf;
  for (char &c : s) {
    if (c == '\t' || c == '\n') {
      c = ' ';
    }
  }
  return s;
}

static void walk(const Handle(XCAFDoc_ShapeTool) &tool, const TDF_Label &label,
                 const TopLoc_Location &loc, const std::string &path, int depth) {
  if (depth > 64) {
    return;
  }
  if (XCAFDoc_ShapeTool::IsAssembly(label)) {
    const gp_Trsf a = loc.Transformation();
    std::printf("assembly\t%s\t%s\t", path.c_str(), name_of(label).c_str());
    for (int r = 1; r <= 3; ++r) {
      for (int c = 1; c <= 4; ++c) {
        std::printf(r + c == 2 ? "%.12g" : " %.12g", a.Value(r, c));
      }
    }
    std::printf("\n");
    TDF_LabelSequence comps;
    XCAFDoc_ShapeTool::GetComponents(label, comps, Standard_False);
    for (Standard_Integer i = 1; i <= comps.Length(); ++i) {
      const TDF_Label c = comps.Value(i);
      TDF_Label referred;
      if (!XCAFDoc_ShapeTool::GetReferredShape(c, referred)) {
        continue;
      }
      std::string n = name_of(c);
      if (n.empty()) {
        n = name_of(referred);
      }
      walk(tool, referred, loc * XCAFDoc_ShapeTool::GetLocation(c), path + "/" + n, depth + 1);
    }
    return;
  }
  const TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
  const std::string product = name_of(label);
  for (TopExp_Explorer sx(shape, TopAbs_SOLID); sx.More(); sx.Next()) {
    const TopoDS_Shape solid = sx.Current();
    GProp_GProps props;
    BRepGProp::VolumeProperties(solid.Located(TopLoc_Location()), props);
    const gp_Trsf t = (loc * solid.Location()).Transformation();
    std::printf("solid\t%s\t%s\t%.9g", path.c_str(), product.c_str(), props.Mass());
    for (int r = 1; r <= 3; ++r) {
      for (int c = 1; c <= 4; ++c) {
        std::printf(" %.12g", t.Value(r, c));
      }
    }
    std::printf("\n");
  }
}

int main(int argc, char **argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: occt_check FILE.step\n");
    return 2;
  }
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  STEPCAFControl_Reader reader;
  reader.SetNameMode(Standard_True);
  if (reader.ReadFile(argv[1]) != IFSelect_RetDone) {
    std::fprintf(stderr, "cannot parse %s\n", argv[1]);
    return 1;
  }
  TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
  reader.ChangeReader().FileUnits(lengths, angles, solid_angles);
  std::printf("unit\t%s\n", lengths.IsEmpty() ? "" : lengths.First().ToCString());
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  XCAFDoc_DocumentTool::SetLengthUnit(doc, 1.0, UnitsMethods_LengthUnit_Millimeter);
  if (!reader.Transfer(doc)) {
    std::fprintf(stderr, "cannot transfer %s\n", argv[1]);
    return 1;
  }
  Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  TDF_LabelSequence roots;
  tool->GetFreeShapes(roots);
  for (Standard_Integer i = 1; i <= roots.Length(); ++i) {
    walk(tool, roots.Value(i), XCAFDoc_ShapeTool::GetLocation(roots.Value(i)),
         name_of(roots.Value(i)), 0);
  }
  app->Close(doc);
  return 0;
}
