"""MeshLab filters of other plugins, as the XML of one <filter> of a .mlx script, for the comparison
scripts and the integration tests (one text each, every parameter given: meshlabserver aborts on a
missing one). The scripts of ConeLOD's own filters are the files in scripts/mlx/."""


def builtin_qem(target_faces=0, target_perc=0):
    """MeshLab's "Simplification: Quadric Edge Collapse Decimation" with its dialog's defaults, to
    `target_faces` faces (or to the fraction `target_perc` of the input when target_faces is 0)."""
    return """ <filter name="Simplification: Quadric Edge Collapse Decimation">
  <Param type="RichInt" value="%d" name="TargetFaceNum"/>
  <Param type="RichFloat" value="%g" name="TargetPerc"/>
  <Param type="RichFloat" value="0.3" name="QualityThr"/>
  <Param type="RichBool" value="false" name="PreserveBoundary"/>
  <Param type="RichFloat" value="1" name="BoundaryWeight"/>
  <Param type="RichBool" value="false" name="PreserveNormal"/>
  <Param type="RichBool" value="false" name="PreserveTopology"/>
  <Param type="RichBool" value="true" name="OptimalPlacement"/>
  <Param type="RichBool" value="false" name="PlanarQuadric"/>
  <Param type="RichFloat" value="0.001" name="PlanarWeight"/>
  <Param type="RichBool" value="false" name="QualityWeight"/>
  <Param type="RichBool" value="true" name="AutoClean"/>
  <Param type="RichBool" value="false" name="Selected"/>
 </filter>
""" % (target_faces, target_perc)


def hausdorff(sampled, target, samples, sample_edges, max_dist="1e+09"):
    """MeshLab's "Hausdorff Distance" from layer `sampled` to layer `target` (layer indices) with
    `samples` samples on vertices, faces and, if `sample_edges`, edges."""
    return """ <filter name="Hausdorff Distance">
  <Param type="RichMesh" value="%s" name="SampledMesh"/>
  <Param type="RichMesh" value="%s" name="TargetMesh"/>
  <Param type="RichBool" value="false" name="SaveSample"/>
  <Param type="RichBool" value="true" name="SampleVert"/>
  <Param type="RichBool" value="%s" name="SampleEdge"/>
  <Param type="RichBool" value="false" name="SampleFauxEdge"/>
  <Param type="RichBool" value="true" name="SampleFace"/>
  <Param type="RichInt" value="%d" name="SampleNum"/>
  <Param type="RichAbsPerc" value="%s" min="0" max="%s" name="MaxDist"/>
 </filter>
""" % (sampled, target, "true" if sample_edges else "false", samples, max_dist, max_dist)


def script(*filters):
    """A whole .mlx script of the given <filter> texts, in order."""
    return "<!DOCTYPE FilterScript>\n<FilterScript>\n%s</FilterScript>\n" % "".join(filters)
