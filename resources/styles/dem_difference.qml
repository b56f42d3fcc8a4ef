<!DOCTYPE qgis PUBLIC 'http://mrcc.com/qgis.dtd' 'SYSTEM'>
<qgis version="3.22.0" styleCategories="AllStyleCategories" hasScaleBasedVisibilityFlag="0" minScale="1e+08" maxScale="0">
  <pipe>
    <rasterrenderer type="singlebandpseudocolor" band="1" opacity="1" alphaBand="-1" classificationMin="-5" classificationMax="5" nodataColor="">
      <rasterTransparency/>
      <minMaxOrigin>
        <limits>None</limits>
        <extent>WholeRaster</extent>
        <statAccuracy>Estimated</statAccuracy>
        <cumulativeCutLower>0.02</cumulativeCutLower>
        <cumulativeCutUpper>0.98</cumulativeCutUpper>
        <stdDevFactor>2</stdDevFactor>
      </minMaxOrigin>
      <rastershader>
        <colorrampshader colorRampType="DISCRETE" classificationMode="1" clip="0" minimumValue="-5" maximumValue="5" labelPrecision="2">
          <item alpha="255" value="-5" label="&lt; −5 m" color="#08306b"/>
          <item alpha="255" value="-3" label="−5 … −3 m" color="#2166ac"/>
          <item alpha="255" value="-2" label="−3 … −2 m" color="#4393c3"/>
          <item alpha="255" value="-1" label="−2 … −1 m" color="#92c5de"/>
          <item alpha="255" value="-0.5" label="−1 … −0.5 m" color="#c6dbef"/>
          <item alpha="255" value="-0.25" label="−0.5 … −0.25 m" color="#e3eef8"/>
          <item alpha="255" value="0.25" label="−0.25 … +0.25 m" color="#ffffbf"/>
          <item alpha="255" value="0.5" label="+0.25 … +0.5 m" color="#fee0b6"/>
          <item alpha="255" value="1" label="+0.5 … +1 m" color="#fdb863"/>
          <item alpha="255" value="2" label="+1 … +2 m" color="#f4a582"/>
          <item alpha="255" value="3" label="+2 … +3 m" color="#d6604d"/>
          <item alpha="255" value="5" label="+3 … +5 m" color="#b2182b"/>
          <item alpha="255" value="inf" label="&gt; +5 m" color="#67001f"/>
        </colorrampshader>
      </rastershader>
    </rasterrenderer>
    <brightnesscontrast brightness="0" contrast="0" gamma="1"/>
    <huesaturation saturation="0" grayscaleMode="0" colorizeOn="0" colorizeRed="255" colorizeGreen="128" colorizeBlue="128" colorizeStrength="100"/>
    <rasterresampler maxOversampling="2"/>
  </pipe>
  <blendMode>0</blendMode>
</qgis>
