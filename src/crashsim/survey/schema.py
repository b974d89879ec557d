"""The ``[survey]`` section of a scenario file: survey files, their mapping to scene items, recorder
tables, the orthophoto underlay and the scene frame (validated and documented like every section)."""

from __future__ import annotations

from ..schema import ArrayOf, Field, Section
from ..units import Kind

__all__ = ["SURVEY", "KINDS", "FORMATS", "MAP_LINE_STYLES"]

#: Styles of a map line (``[[map.lines]]``); crashsim.plotting draws each in its conventional way.
MAP_LINE_STYLES = ("edge", "lane", "centre", "kerb", "stop", "other")

#: What a layer or code can be. line: a [[map.lines]] line (needs style); obstacle: an [[obstacles]]
#: item; zone: a [[runout.zones]] friction zone (closed outlines, needs friction); mark: an
#: [[evidence.marks]] tyre mark; rest: an [[evidence.rest]] item (measured points of a body);
#: impact_point: [evidence.impact_point]; gouge, debris: drawn only (map lines of style other);
#: ignore: mapped on purpose and left out.
KINDS = ("line", "obstacle", "zone", "mark", "rest", "impact_point", "gouge", "debris", "surface", "ignore")
FORMATS = ("dxf", "points", "geojson")

MAPPING = Section("map", [
    Field("match", "str", example="KERB*",
          description="Which entities: a DXF layer name, a point code or a GeoJSON property value; * and ? are "
                      "wildcards; case is ignored. An entity is taken by the first entry that matches it"),
    Field("kind", choices=KINDS, example="obstacle",
          description="What they are: line, obstacle, zone, mark, rest, impact_point, gouge, debris (drawn only), "
                      "surface (a TIN of DXF 3DFACEs: the plane fitted to its vertices, in the scene frame, gives "
                      "runout.grade and runout.cross_slope, which the file then does not give) or ignore"),
    Field("name", "str", default="", description="Name of the items made (default: the layer or code and the "
                                                  "entity handle or point numbers)"),
    Field("style", "str", required=False, example="kerb",
          description="kind = line: edge, lane, centre, kerb, stop or other (as map.lines.style)"),
    Field("color", "str", required=False, example="#7f7f7f", description="kind = line, gouge, debris: colour"),
    Field("thickness", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, example="0.3 m",
          description="kind = obstacle: width of a line obstacle (as obstacles.thickness)"),
    Field("size", Kind.LENGTH, minimum=0, exclusive_minimum=True, default="0.3 m",
          description="A POINT as an obstacle (a post or pole) becomes an octagon of this diameter; a point gouge or "
                      "debris is drawn as a square of this side"),
    Field("friction", "float", required=False, minimum=0, maximum=2, exclusive_minimum=True, example="0.35",
          description="kind = zone: friction coefficient inside the outlines"),
    Field("wheel", "str", required=False, example="car/1/left", description="kind = mark: as evidence.marks.wheel"),
    Field("phase", choices=("runout", "approach"), required=False, description="kind = mark: as evidence.marks.phase"),
    Field("sliding_only", "bool", required=False, description="kind = mark: as evidence.marks.sliding_only"),
    Field("body", "str", required=False, example="car", description="kind = rest: the body whose rest was measured"),
    Field("at", "str", required=False, example="front_left, front_right, rear_right, rear_left",
          description="kind = rest: the named points of the body (evidence.rest.points.at) that the vertices of "
                      "each polyline, or the points of the layer in file order, are, comma-separated; absent: one "
                      "point, the CG"),
    Field("tolerance", Kind.LENGTH, required=False, minimum=0, example="0.3 m",
          description="kind = mark, rest, impact_point: as the evidence item's tolerance"),
    Field("heading_tolerance", Kind.ANGLE, required=False, minimum=0, example="5 deg",
          description="kind = rest: as evidence.rest.heading_tolerance"),
    Field("sigma", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, example="0.1 m",
          description="kind = mark, rest, impact_point: the evidence item's sigma (fit, posterior)"),
    Field("heading_sigma", Kind.ANGLE, required=False, minimum=0, exclusive_minimum=True, example="2 deg",
          description="kind = rest: as evidence.rest.heading_sigma"),
], description="Which entities of the file become which scene items")

FILE = Section("file", [
    Field("file", "str", example="survey/scene.dxf", description="The survey file, relative to the scenario file"),
    Field("format", choices=FORMATS, required=False,
          description="dxf, points (total-station CSV/TXT) or geojson; default from the extension (.dxf; .csv, "
                      ".txt, .asc, .pnezd; .geojson, .json)"),
    Field("units", "str", required=False, example="m",
          description="Unit of the file's coordinates: m, mm, cm, ft, us_ft (US survey foot), in, yd. DXF: "
                      "default from $INSUNITS, and an error where both are given and differ; points: required; "
                      "GeoJSON: from its CRS"),
    Field("columns", "str", default="PNEZD",
          description="points: column letters P number, N northing, E easting (or X, Y), Z, D code, - skip"),
    Field("join", choices=("run", "code"), default="run",
          description="points: strings are runs of consecutive points of a code (run), or all points of a code in "
                      "file order (code); BEG/END/CLO control words after the code start, end and close strings"),
    Field("breaklines", "str", required=False, example="survey/topo.brk",
          description="points: a file of chains of point numbers (12-13-14) giving the strings instead"),
    Field("crs", "str", required=False, example="EPSG:4326",
          description="GeoJSON: the CRS of its coordinates (default its crs member, else WGS 84 lon/lat)"),
    Field("layer_property", "str", default="layer",
          description="GeoJSON: the property whose value is matched as the feature's layer"),
    Field("chord_tolerance", Kind.LENGTH, minimum=1e-6, maximum=1, default="1 cm",
          description="DXF: largest distance of a chord from the arc, circle or spline it replaces"),
], subsections=[ArrayOf("map", MAPPING, min_items=1, description="The mapping of its layers or codes")],
   description="One survey file (DXF drawing, total-station points or GeoJSON) and its mapping")

RECORDER = Section("recorder", [
    Field("file", "str", example="survey/ecm.csv", description="The recorder table (CSV with a header row), "
                                                               "relative to the scenario file"),
    Field("body", "str", example="tractor", description="Body carrying the recorder (as evidence.recorder.body)"),
    Field("name", "str", default="", description="Label for the report"),
    Field("tolerance", Kind.SPEED, minimum=0, exclusive_minimum=True, example="1 mph",
          description="As evidence.recorder.tolerance"),
    Field("sigma", Kind.SPEED, required=False, minimum=0, exclusive_minimum=True, example="1 mph",
          description="As evidence.recorder.sigma"),
    Field("time_offset", Kind.TIME, default="0 s", minimum=-5, maximum=5,
          description="As evidence.recorder.time_offset (a fit unknown by its path evidence.recorder[i].time_offset)"),
    Field("time", "str", example="Time (s)", description="Column of the sample time (impact at 0, before it "
                                                         "negative; samples more than 5 s after it are left out)"),
    Field("speed", "str", example="Speed, vehicle indicated (km/h)", description="Column of the speed"),
    Field("time_unit", "str", default="s", description="Unit of the time column (s, ms)"),
    Field("speed_unit", "str", default="km/h", description="Unit of the speed column (km/h, mph, m/s)"),
    Field("brake", "str", required=False, example="Service brake", description="Column of the service brake"),
    Field("abs", "str", required=False, example="ABS activity", description="Column of ABS activity"),
    Field("accelerator", "str", required=False, description="Column of the accelerator pedal (checked, reported)"),
    Field("steering", "str", required=False, description="Column of the steering input (checked, reported)"),
    Field("yaw_rate", "str", required=False, description="Column of the yaw rate (checked, reported)"),
    Field("on", "str", default="on, 1, yes, true, engaged, active",
          description="Values of the brake and ABS columns that mean on (comma-separated, any case); with the "
                      "brake or ABS on a sample is a lower bound of the speed"),
], description="A pre-crash recorder table read into [[evidence.recorder]]")

CONTROL = Section("control", [
    Field("pixel", "float", n=2, example="[120.5, 86.0]", description="Image column and row (0, 0: the top left "
                                                                      "corner of the top left pixel)"),
    Field("position", Kind.LENGTH, n=2, example='["12.0 m", "3.5 m"]',
          description="Where the pixel lies, in the survey's axes (as survey.origin)"),
], description="A control point of the underlay")

UNDERLAY = Section("underlay", [
    Field("image", "str", example="survey/ortho.png", description="The image (PNG, JPEG, or a GeoTIFF with the "
                                                                  "geotiff extra), relative to the scenario file"),
    Field("world_file", "str", required=False,
          description="Its world file (.pgw, .jgw, .tfw, .wld); default the image's own where it exists"),
    Field("units", "str", default="m", description="Unit of the world file or GeoTIFF coordinates"),
    Field("fit", choices=("similarity", "affine"), default="similarity",
          description="With control points: a similarity (scale, rotation, shift; 2+ points) or an affine (3+)"),
    Field("tolerance", Kind.LENGTH, minimum=0, exclusive_minimum=True, default="0.1 m",
          description="Largest residual of a control point"),
    Field("opacity", "float", minimum=0, maximum=1, default=0.6, description="Opacity of the image"),
    Field("clip", "bool", default=True,
          description="Draw only the part of the image in and around the view (half its span each side)"),
], subsections=[ArrayOf("control", CONTROL, required=False, description="Control points instead of a world file")],
    required=False, description="A scaled image drawn under the scene figures")

IMPORTED = Section("imported", [
    Field("file", "str", description="Survey file"),
    Field("layer", "str", default="", description="Layer, code or property value"),
    Field("ref", "str", default="", description="Entity handle, point numbers or feature index"),
    Field("type", "str", default="", description="Entity type"),
    Field("kind", "str", description="What it became"),
    Field("target", "str", default="", description="The scene item it became (map.lines[3], evidence.rest[0])"),
    Field("note", "str", default="", description="A warning or note of the import"),
    Field("key", "str", default="", description="The key that made it (survey.files[1].map[0], survey.recorders[0]): "
                                                "errors of the item name it"),
], description="Written by crashsim when the survey is read (fit --write-best keeps it): an imported item and its "
               "source; with these present the files are not read again")

SURVEY = Section("survey", [
    Field("origin", Kind.LENGTH, n=2, default=["0 m", "0 m"], example='["1455000 survey_foot", "538400 survey_foot"]',
          description="Survey coordinates (easting or x, northing or y) of the scene origin; write US survey feet as "
                      "survey_foot"),
    Field("rotation", Kind.ANGLE, default="0 deg",
          description="Direction of the scene's +X axis in the survey's axes, counter-clockwise from the survey's +x"),
    Field("crs", "str", required=False, example="EPSG:32633",
          description="Projected CRS of the survey's axes (GeoJSON is projected into it)"),
    Field("units", "str", required=False, example="us_ft",
          description="Unit of CAD and GeoJSON exports (default: the first survey file's, else m)"),
], subsections=[
    ArrayOf("files", FILE, required=False, description="Survey files and their mappings"),
    ArrayOf("recorders", RECORDER, required=False, description="Recorder tables"),
    UNDERLAY,
    ArrayOf("imported", IMPORTED, required=False, description="Written by crashsim (do not write by hand)"),
], required=False, description="The scene from survey files: drawings, total-station points, GeoJSON, recorder "
                               "tables and an orthophoto, placed by a scene frame")
