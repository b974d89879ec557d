"""Scene data in: survey drawings (DXF), total-station points, GeoJSON, recorder tables and
orthophotos, placed in the scene frame; and the reconstruction back out to CAD (DXF, GeoJSON).

File formats live here, at the edge: readers convert units once and hand the scenario plain
metres in the scene frame (:func:`expand_survey`). Optional heavy libraries (ezdxf, pyproj,
rasterio) are imported inside the functions that need them.
"""

from .entities import Entity, SurveyData
from .frame import SceneFrame, UNIT_METRES
from .mapping import expand_survey, is_expanded, load_scene_data, read_survey_file

__all__ = ["Entity", "SurveyData", "SceneFrame", "UNIT_METRES", "expand_survey", "is_expanded", "load_scene_data",
           "read_survey_file"]
