<?xml version="1.0" encoding="utf-8"?>
<!DOCTYPE TS>
<TS version="2.1" language="de_DE" sourcelanguage="en">
    <context>
        <name>photodem</name>
        <message>
            <source>Create project</source>
            <extracomment>project_create: name</extracomment>
            <translation>Projekt anlegen</translation>
        </message>
        <message>
            <source>Project</source>
            <extracomment>project_create: group; project_info: group; stereo_models: group</extracomment>
            <translation>Projekt</translation>
        </message>
        <message>
            <source>Creates a PhotoDEM project (project.toml + edits.gpkg) from a folder of images and their orientation: an OPK CSV or text file with the camera YAML (orthority format), or an OpenSfM/ODM reconstruction.json. The block is validated and its stereo models are detected (overlap ≥ 25 %, B/H 0.2–1.2, in-strip neighbours first).</source>
            <extracomment>project_create: help</extracomment>
            <translation>Legt ein PhotoDEM-Projekt (project.toml + edits.gpkg) aus einem Bildordner und der Orientierung der Bilder an: eine OPK-CSV- oder Textdatei mit der Kamera-YAML (Orthority-Format) oder eine OpenSfM/ODM-reconstruction.json. Der Bildverband wird geprüft und seine Stereomodelle werden bestimmt (Überlappung ≥ 25 %, B/H 0,2–1,2, Nachbarn im selben Streifen zuerst).</translation>
        </message>
        <message>
            <source>Images folder</source>
            <extracomment>project_create.images: description</extracomment>
            <translation>Bildordner</translation>
        </message>
        <message>
            <source>Exterior orientation (OPK CSV/text or reconstruction.json)</source>
            <extracomment>project_create.exterior: description</extracomment>
            <translation>Äußere Orientierung (OPK-CSV/-Text oder reconstruction.json)</translation>
        </message>
        <message>
            <source>x, y, z in the project CRS; omega, phi, kappa PATB (camera to world).</source>
            <extracomment>project_create.exterior: help</extracomment>
            <translation>x, y, z im Projekt-KBS; Omega, Phi, Kappa nach PATB (Kamera → Objektraum).</translation>
        </message>
        <message>
            <source>Interior orientation (camera YAML)</source>
            <extracomment>project_create.interior: description</extracomment>
            <translation>Innere Orientierung (Kamera-YAML)</translation>
        </message>
        <message>
            <source>Orthority interior-parameter YAML; not needed for OpenSfM.</source>
            <extracomment>project_create.interior: help</extracomment>
            <translation>YAML mit den Parametern der inneren Orientierung (Orthority); für OpenSfM nicht nötig.</translation>
        </message>
        <message>
            <source>Project CRS</source>
            <extracomment>project_create.crs: description; project_info output crs</extracomment>
            <translation>Projekt-KBS</translation>
        </message>
        <message>
            <source>Optional when a .prj file lies beside the exterior file.</source>
            <extracomment>project_create.crs: help</extracomment>
            <translation>Optional, wenn neben der Datei der äußeren Orientierung eine .prj-Datei liegt.</translation>
        </message>
        <message>
            <source>Angle unit of omega, phi, kappa</source>
            <extracomment>project_create.angle_unit: description</extracomment>
            <translation>Winkeleinheit von Omega, Phi, Kappa</translation>
        </message>
        <message>
            <source>degrees</source>
            <extracomment>project_create.angle_unit: option</extracomment>
            <translation>Grad</translation>
        </message>
        <message>
            <source>gon</source>
            <extracomment>project_create.angle_unit: option</extracomment>
            <translation>Gon</translation>
        </message>
        <message>
            <source>radians</source>
            <extracomment>project_create.angle_unit: option</extracomment>
            <translation>Radiant</translation>
        </message>
        <message>
            <source>DEM for terrain heights and footprints</source>
            <extracomment>project_create.dem: description; stereo_models.dem: description</extracomment>
            <translation>Geländemodell für Geländehöhen und Bildfußabdrücke</translation>
        </message>
        <message>
            <source>Mean terrain height [m]</source>
            <extracomment>project_create.terrain_height: description</extracomment>
            <translation>Mittlere Geländehöhe [m]</translation>
        </message>
        <message>
            <source>Used when no DEM is given.</source>
            <extracomment>project_create.terrain_height: help</extracomment>
            <translation>Wird verwendet, wenn kein Geländemodell angegeben ist.</translation>
        </message>
        <message>
            <source>Project folder</source>
            <extracomment>project_create output project; project_create.output: description; project_info.project: description; stereo_models.project: description; synthetic_block output project</extracomment>
            <translation>Projektordner</translation>
        </message>
        <message>
            <source>Number of images</source>
            <extracomment>project_create output images; synthetic_block output images</extracomment>
            <translation>Anzahl der Bilder</translation>
        </message>
        <message>
            <source>Number of cameras</source>
            <extracomment>project_create output cameras</extracomment>
            <translation>Anzahl der Kameras</translation>
        </message>
        <message>
            <source>Names of the stereo models</source>
            <extracomment>project_create output models</extracomment>
            <translation>Namen der Stereomodelle</translation>
        </message>
        <message>
            <source>Validation warnings</source>
            <extracomment>project_create output warnings</extracomment>
            <translation>Warnungen der Prüfung</translation>
        </message>
        <message>
            <source>Project information</source>
            <extracomment>project_info: name</extracomment>
            <translation>Projektinformationen</translation>
        </message>
        <message>
            <source>Lists a project's CRS, images (position, angles in degrees, whether the file exists), cameras and stereo models (B/H, overlap %, GSD, flying height above ground), and the result of its validation.</source>
            <extracomment>project_info: help</extracomment>
            <translation>Listet KBS, Bilder (Position, Winkel in Grad, ob die Datei vorhanden ist), Kameras und Stereomodelle (B/H, Überlappung in %, Bodenauflösung, Flughöhe über Grund) eines Projekts sowie das Ergebnis seiner Prüfung auf.</translation>
        </message>
        <message>
            <source>Project name</source>
            <extracomment>project_info output name</extracomment>
            <translation>Projektname</translation>
        </message>
        <message>
            <source>Images</source>
            <extracomment>project_info output images</extracomment>
            <translation>Bilder</translation>
        </message>
        <message>
            <source>Cameras</source>
            <extracomment>project_info output cameras</extracomment>
            <translation>Kameras</translation>
        </message>
        <message>
            <source>Stereo models</source>
            <extracomment>project_info output models; stereo_models output models; stereo_models: name</extracomment>
            <translation>Stereomodelle</translation>
        </message>
        <message>
            <source>Validation errors and warnings</source>
            <extracomment>project_info output validation</extracomment>
            <translation>Fehler und Warnungen der Prüfung</translation>
        </message>
        <message>
            <source>Sets the stereo models of a project: detected automatically from the image footprints (overlap, B/H and strip thresholds as given; in-strip neighbours first) and/or chosen by hand as pairs of images. The models are written to project.toml; the images, orientations and edits are not touched.</source>
            <extracomment>stereo_models: help</extracomment>
            <translation>Legt die Stereomodelle eines Projekts fest: automatisch aus den Bildfußabdrücken ermittelt (Überlappung, B/H und Streifenschwellen wie angegeben; Nachbarn im Streifen zuerst) und/oder von Hand als Bildpaare gewählt. Die Modelle werden in project.toml geschrieben; Bilder, Orientierungen und Editierungen bleiben unverändert.</translation>
        </message>
        <message>
            <source>Detect models automatically</source>
            <extracomment>stereo_models.detect: description</extracomment>
            <translation>Modelle automatisch ermitteln</translation>
        </message>
        <message>
            <source>Minimum overlap [%]</source>
            <extracomment>stereo_models.min_overlap: description</extracomment>
            <translation>Mindestüberlappung [%]</translation>
        </message>
        <message>
            <source>Share of the smaller footprint that both images cover.</source>
            <extracomment>stereo_models.min_overlap: help</extracomment>
            <translation>Anteil des kleineren Fußabdrucks, den beide Bilder abdecken.</translation>
        </message>
        <message>
            <source>Minimum B/H</source>
            <extracomment>stereo_models.b_h_min: description</extracomment>
            <translation>Kleinstes B/H</translation>
        </message>
        <message>
            <source>Maximum B/H</source>
            <extracomment>stereo_models.b_h_max: description</extracomment>
            <translation>Größtes B/H</translation>
        </message>
        <message>
            <source>Strip direction tolerance [°]</source>
            <extracomment>stereo_models.strip_angle_tolerance: description</extracomment>
            <translation>Toleranz der Streifenrichtung [°]</translation>
        </message>
        <message>
            <source>A pair is in-strip when its base is this close to the strip direction.</source>
            <extracomment>stereo_models.strip_angle_tolerance: help</extracomment>
            <translation>Ein Paar liegt im Streifen, wenn seine Basis höchstens so weit von der Streifenrichtung abweicht.</translation>
        </message>
        <message>
            <source>In-strip models only</source>
            <extracomment>stereo_models.in_strip_only: description</extracomment>
            <translation>Nur Modelle im Streifen</translation>
        </message>
        <message>
            <source>Manual pairs</source>
            <extracomment>stereo_models.manual: description</extracomment>
            <translation>Manuelle Bildpaare</translation>
        </message>
        <message>
            <source>Image pairs 'left,right; left,right' (image names or their short labels as in the model names), added as kind 'manual'.</source>
            <extracomment>stereo_models.manual: help</extracomment>
            <translation>Bildpaare 'links,rechts; links,rechts' (Bildnamen oder ihre Kurzbezeichnungen wie in den Modellnamen), als Art 'manual' hinzugefügt.</translation>
        </message>
        <message>
            <source>Default: the project's mean terrain height.</source>
            <extracomment>stereo_models.dem: help</extracomment>
            <translation>Standard: die mittlere Geländehöhe des Projekts.</translation>
        </message>
        <message>
            <source>Number of stereo models</source>
            <extracomment>stereo_models output count; synthetic_block output models</extracomment>
            <translation>Anzahl der Stereomodelle</translation>
        </message>
        <message>
            <source>Images without a stereo partner</source>
            <extracomment>stereo_models output unpaired</extracomment>
            <translation>Bilder ohne Stereopartner</translation>
        </message>
        <message>
            <source>Synthetic block with ground truth</source>
            <extracomment>synthetic_block: name</extracomment>
            <translation>Synthetischer Bildverband mit Referenzdaten</translation>
        </message>
        <message>
            <source>Synthetic data</source>
            <extracomment>synthetic_block: group</extracomment>
            <translation>Synthetische Daten</translation>
        </message>
        <message>
            <source>Generates a deterministic synthetic aerial block: terrain (gentle, dunes or steep), an embankment and a ditch with breaklines, buildings, trees and a forest patch, textured ground with bright check-point discs, frame images in two or more strips (60 % forward, 30 % side overlap) rendered by ray casting against the true DSM. Writes a complete project (project.toml, images, edits.gpkg, in-strip stereo models) and the ground truth (DTM, DSM, land cover, building footprints, 3-D breaklines, check points) below truth/. The same seed always gives the same block.</source>
            <extracomment>synthetic_block: help</extracomment>
            <translation>Erzeugt einen deterministischen synthetischen Bildflug: Gelände (flach, Dünen oder steil), einen Damm und einen Graben mit Bruchkanten, Gebäude, Bäume und ein Waldstück, texturierten Boden mit hellen Kontrollpunktscheiben sowie Reihenmessbilder in zwei oder mehr Streifen (60 % Längs-, 30 % Querüberdeckung), gerendert durch Strahlverfolgung gegen das wahre Oberflächenmodell. Schreibt ein vollständiges Projekt (project.toml, Bilder, edits.gpkg, Stereomodelle im Streifen) und die Referenzdaten (Geländemodell, Oberflächenmodell, Landbedeckung, Gebäudegrundrisse, 3D-Bruchkanten, Kontrollpunkte) unter truth/. Derselbe Startwert ergibt immer denselben Bildverband.</translation>
        </message>
        <message>
            <source>Output project folder</source>
            <extracomment>synthetic_block.output: description</extracomment>
            <translation>Ausgabe-Projektordner</translation>
        </message>
        <message>
            <source>Block size</source>
            <extracomment>synthetic_block.size: description</extracomment>
            <translation>Größe des Bildverbands</translation>
        </message>
        <message>
            <source>tiny: 224×288 px images (tests); small: 704×1000 px (demo); medium: 1408×2000 px; large: 2400×3400 px (≈ 8 Mpx).</source>
            <extracomment>synthetic_block.size: help</extracomment>
            <translation>winzig: Bilder mit 224×288 px (Tests); klein: 704×1000 px (Demo); mittel: 1408×2000 px; groß: 2400×3400 px (≈ 8 Mpx).</translation>
        </message>
        <message>
            <source>tiny</source>
            <extracomment>synthetic_block.size: option</extracomment>
            <translation>winzig</translation>
        </message>
        <message>
            <source>small</source>
            <extracomment>synthetic_block.size: option</extracomment>
            <translation>klein</translation>
        </message>
        <message>
            <source>medium</source>
            <extracomment>synthetic_block.size: option</extracomment>
            <translation>mittel</translation>
        </message>
        <message>
            <source>large</source>
            <extracomment>synthetic_block.size: option</extracomment>
            <translation>groß</translation>
        </message>
        <message>
            <source>Terrain type</source>
            <extracomment>synthetic_block.terrain: description</extracomment>
            <translation>Geländetyp</translation>
        </message>
        <message>
            <source>steep: relief &gt; 100 m with slopes of 45° and more (flown 2.5× higher).</source>
            <extracomment>synthetic_block.terrain: help</extracomment>
            <translation>steil: Relief &gt; 100 m mit Hangneigungen von 45° und mehr (2,5-fache Flughöhe).</translation>
        </message>
        <message>
            <source>gentle</source>
            <extracomment>synthetic_block.terrain: option</extracomment>
            <translation>flach</translation>
        </message>
        <message>
            <source>dunes</source>
            <extracomment>synthetic_block.terrain: option</extracomment>
            <translation>Dünen</translation>
        </message>
        <message>
            <source>steep</source>
            <extracomment>synthetic_block.terrain: option</extracomment>
            <translation>steil</translation>
        </message>
        <message>
            <source>Random seed</source>
            <extracomment>synthetic_block.seed: description</extracomment>
            <translation>Startwert des Zufallsgenerators</translation>
        </message>
        <message>
            <source>Direction of the field furrows [°]</source>
            <extracomment>synthetic_block.texture_direction: description</extracomment>
            <translation>Richtung der Ackerfurchen [°]</translation>
        </message>
        <message>
            <source>Counter-clockwise from the flight direction (+X): 0 = furrows along the base, 90 = across it.</source>
            <extracomment>synthetic_block.texture_direction: help</extracomment>
            <translation>Gegen den Uhrzeigersinn von der Flugrichtung (+X): 0 = Furchen entlang der Basis, 90 = quer dazu.</translation>
        </message>
        <message>
            <source>True DTM</source>
            <extracomment>synthetic_block output truth_dtm</extracomment>
            <translation>Wahres Geländemodell (DGM)</translation>
        </message>
        <message>
            <source>True DSM</source>
            <extracomment>synthetic_block output truth_dsm</extracomment>
            <translation>Wahres Oberflächenmodell (DOM)</translation>
        </message>
        <message>
            <source>Land cover (1 open, 2 road, 3 building, 4 tree/forest, 5 water/ditch, 6 embankment, 7 field)</source>
            <extracomment>synthetic_block output truth_landcover</extracomment>
            <translation>Landbedeckung (1 offen, 2 Straße, 3 Gebäude, 4 Baum/Wald, 5 Wasser/Graben, 6 Damm, 7 Acker)</translation>
        </message>
        <message>
            <source>Building footprints</source>
            <extracomment>synthetic_block output truth_buildings</extracomment>
            <translation>Gebäudegrundrisse</translation>
        </message>
        <message>
            <source>3-D breaklines</source>
            <extracomment>synthetic_block output truth_breaklines</extracomment>
            <translation>3D-Bruchkanten</translation>
        </message>
        <message>
            <source>Check points (3-D)</source>
            <extracomment>synthetic_block output truth_checkpoints</extracomment>
            <translation>Kontrollpunkte (3D)</translation>
        </message>
        <message>
            <source>Ground sample distance [m]</source>
            <extracomment>synthetic_block output gsd_m</extracomment>
            <translation>Bodenauflösung (GSD) [m]</translation>
        </message>
        <message>
            <source>Flying height above mean terrain [m]</source>
            <extracomment>synthetic_block output flying_height_m</extracomment>
            <translation>Flughöhe über mittlerem Gelände [m]</translation>
        </message>
        <message>
            <source>Epipolar pair</source>
            <extracomment>epipolar_pair: name</extracomment>
            <translation>Epipolarbildpaar</translation>
        </message>
        <message>
            <source>Geometry</source>
            <extracomment>epipolar_pair: group</extracomment>
            <translation>Geometrie</translation>
        </message>
        <message>
            <source>Resamples the two images of a stereo model to normal-case (epipolar) geometry: both images share one rotation with x along the base, so a ground point has the same row in both. Writes left.tif and right.tif (input bands plus an alpha band), left_map.tif and right_map.tif (original col, row of every epipolar pixel, NaN outside) and epipolar.json (homographies, focal length in px, base, sizes) for matching and triangulation.</source>
            <extracomment>epipolar_pair: help</extracomment>
            <translation>Bildet die beiden Bilder eines Stereomodells in den Normalfall (Epipolargeometrie) um: beide Bilder erhalten dieselbe Drehung mit x entlang der Basis, sodass ein Geländepunkt in beiden Bildern in derselben Zeile liegt. Schreibt left.tif und right.tif (Eingangskanäle plus Alphakanal), left_map.tif und right_map.tif (ursprüngliche Spalte, Zeile jedes Epipolarpixels, außerhalb NaN) und epipolar.json (Homographien, Kamerakonstante in px, Basis, Größen) für Bildzuordnung und Vorwärtsschnitt.</translation>
        </message>
        <message>
            <source>Project folder or project.toml</source>
            <extracomment>epipolar_pair.project: description; match_model.project: description</extracomment>
            <translation>Projektordner oder project.toml</translation>
        </message>
        <message>
            <source>Stereo model</source>
            <extracomment>epipolar_pair.model: description; match_model.model: description</extracomment>
            <translation>Stereomodell</translation>
        </message>
        <message>
            <source>Output folder</source>
            <extracomment>dem_compare.output: description; dem_profile.output: description; epipolar_pair output folder; epipolar_pair.output: description; match_model.output: description; point_compare.output: description</extracomment>
            <translation>Ausgabeordner</translation>
        </message>
        <message>
            <source>Default: &lt;project&gt;/products/epipolar/&lt;model&gt;/. Must not exist or be empty.</source>
            <extracomment>epipolar_pair.output: help</extracomment>
            <translation>Vorgabe: &lt;Projekt&gt;/products/epipolar/&lt;Modell&gt;/. Darf nicht existieren oder muss leer sein.</translation>
        </message>
        <message>
            <source>Resolution scale</source>
            <extracomment>epipolar_pair.scale: description</extracomment>
            <translation>Auflösungsfaktor</translation>
        </message>
        <message>
            <source>Epipolar pixel density relative to the originals (0.5 = half resolution).</source>
            <extracomment>epipolar_pair.scale: help</extracomment>
            <translation>Pixeldichte der Epipolarbilder relativ zu den Originalen (0,5 = halbe Auflösung).</translation>
        </message>
        <message>
            <source>Left epipolar image</source>
            <extracomment>epipolar_pair output left; stereo_disparity.left: description</extracomment>
            <translation>Linkes Epipolarbild</translation>
        </message>
        <message>
            <source>Right epipolar image</source>
            <extracomment>epipolar_pair output right; stereo_disparity.right: description</extracomment>
            <translation>Rechtes Epipolarbild</translation>
        </message>
        <message>
            <source>Left map to original pixels (col, row)</source>
            <extracomment>epipolar_pair output left_map</extracomment>
            <translation>Linke Zuordnung zu den Originalpixeln (Spalte, Zeile)</translation>
        </message>
        <message>
            <source>Right map to original pixels (col, row)</source>
            <extracomment>epipolar_pair output right_map</extracomment>
            <translation>Rechte Zuordnung zu den Originalpixeln (Spalte, Zeile)</translation>
        </message>
        <message>
            <source>epipolar.json</source>
            <extracomment>epipolar_pair output metadata</extracomment>
            <translation>epipolar.json</translation>
        </message>
        <message>
            <source>Largest y-parallax of check points (px)</source>
            <extracomment>epipolar_pair output y_parallax_check_px</extracomment>
            <translation>Größte y-Parallaxe der Kontrollpunkte (px)</translation>
        </message>
        <message>
            <source>Epipolar image size [w, h] (left)</source>
            <extracomment>epipolar_pair output size</extracomment>
            <translation>Größe des Epipolarbilds [B, H] (links)</translation>
        </message>
        <message>
            <source>Compare DEM with reference</source>
            <extracomment>dem_compare: name</extracomment>
            <translation>DGM mit Referenzmodell vergleichen</translation>
        </message>
        <message>
            <source>Quality control</source>
            <extracomment>dem_compare: group; dem_profile: group; point_compare: group</extracomment>
            <translation>Qualitätskontrolle</translation>
        </message>
        <message>
            <source>Compares a DEM (DSM or DTM) with a reference DEM on their common area; the reference may have another grid, extent or CRS (the DEM is resampled onto it). Optionally co-registers the DEM first (horizontal shift and vertical bias after Nuth &amp; Kääb, estimated on stable terrain). Writes the difference model Δh = DEM − reference (with a QGIS style), a hillshade and a slope raster of the DEM, statistics (mean, median, std, RMS, NMAD, quantiles of |Δh|, 0.5 m classes) overall, per class and per slope class, in m and in ‰ of the flying height, and an HTML report with plots.</source>
            <extracomment>dem_compare: help</extracomment>
            <translation>Vergleicht ein Höhenmodell (DOM oder DGM) im gemeinsamen Gebiet mit einem Referenzmodell; das Referenzmodell darf ein anderes Raster, eine andere Ausdehnung oder ein anderes KBS haben (das Höhenmodell wird darauf umgerechnet). Optional wird das Höhenmodell vorher koregistriert (Lageverschiebung und Höhenversatz nach Nuth &amp; Kääb, geschätzt auf stabilem Gelände). Schreibt das Differenzmodell Δh = Höhenmodell − Referenz (mit QGIS-Stil), eine Schummerung und ein Neigungsraster des Höhenmodells, Statistiken (Mittel, Median, Standardabweichung, RMS, NMAD, Quantile von |Δh|, 0,5-m-Klassen) insgesamt, je Klasse und je Neigungsklasse, in m und in ‰ der Flughöhe, sowie einen HTML-Bericht mit Diagrammen.</translation>
        </message>
        <message>
            <source>DEM to check</source>
            <extracomment>dem_compare.dem: description; point_compare.dem: description</extracomment>
            <translation>Zu prüfendes Höhenmodell</translation>
        </message>
        <message>
            <source>Reference DEM</source>
            <extracomment>dem_compare.reference: description</extracomment>
            <translation>Referenzmodell</translation>
        </message>
        <message>
            <source>Receives difference.tif (+ .qml style), hillshade.tif, slope.tif, report.html, stats.json and stats.csv.</source>
            <extracomment>dem_compare.output: help</extracomment>
            <translation>Erhält difference.tif (+ .qml-Stil), hillshade.tif, slope.tif, report.html, stats.json und stats.csv.</translation>
        </message>
        <message>
            <source>Co-register before comparing</source>
            <extracomment>dem_compare.coregister: description</extracomment>
            <translation>Vor dem Vergleich koregistrieren</translation>
        </message>
        <message>
            <source>Estimate and remove a horizontal shift and a vertical bias (Nuth &amp; Kääb) on stable terrain first.</source>
            <extracomment>dem_compare.coregister: help</extracomment>
            <translation>Zuerst Lageverschiebung und Höhenversatz (Nuth &amp; Kääb) auf stabilem Gelände schätzen und entfernen.</translation>
        </message>
        <message>
            <source>Stable terrain (mask raster or polygons)</source>
            <extracomment>dem_compare.stable: description</extracomment>
            <translation>Stabiles Gelände (Maskenraster oder Polygone)</translation>
        </message>
        <message>
            <source>Where the terrain has not changed (co-registration only): a raster (non-zero = stable) or polygons. Default: the whole common area.</source>
            <extracomment>dem_compare.stable: help</extracomment>
            <translation>Wo sich das Gelände nicht verändert hat (nur für die Koregistrierung): ein Raster (ungleich null = stabil) oder Polygone. Standard: das ganze gemeinsame Gebiet.</translation>
        </message>
        <message>
            <source>Classes (polygons or raster)</source>
            <extracomment>dem_compare.classes: description</extracomment>
            <translation>Klassen (Polygone oder Raster)</translation>
        </message>
        <message>
            <source>Statistics per class: a class raster such as land cover, or polygons with a class attribute.</source>
            <extracomment>dem_compare.classes: help</extracomment>
            <translation>Statistik je Klasse: ein Klassenraster wie die Landbedeckung oder Polygone mit einem Klassenattribut.</translation>
        </message>
        <message>
            <source>Class attribute of the polygons</source>
            <extracomment>dem_compare.class_field: description</extracomment>
            <translation>Klassenattribut der Polygone</translation>
        </message>
        <message>
            <source>Attribute of the class polygons that names the class.</source>
            <extracomment>dem_compare.class_field: help</extracomment>
            <translation>Attribut der Klassenpolygone, das die Klasse benennt.</translation>
        </message>
        <message>
            <source>Flying height above ground [m]</source>
            <extracomment>dem_compare.flying_height: description; point_compare.flying_height: description</extracomment>
            <translation>Flughöhe über Grund [m]</translation>
        </message>
        <message>
            <source>For the statistics in ‰ of the flying height.</source>
            <extracomment>dem_compare.flying_height: help; point_compare.flying_height: help</extracomment>
            <translation>Für die Statistik in ‰ der Flughöhe.</translation>
        </message>
        <message>
            <source>Statistics of Δh [m]</source>
            <extracomment>dem_compare output stats</extracomment>
            <translation>Statistik von Δh [m]</translation>
        </message>
        <message>
            <source>Co-registration shift dx, dy, dz [m]</source>
            <extracomment>dem_compare output shift</extracomment>
            <translation>Verschiebung der Koregistrierung dx, dy, dz [m]</translation>
        </message>
        <message>
            <source>Statistics per class</source>
            <extracomment>dem_compare output per_class</extracomment>
            <translation>Statistik je Klasse</translation>
        </message>
        <message>
            <source>Statistics per slope class</source>
            <extracomment>dem_compare output per_slope</extracomment>
            <translation>Statistik je Neigungsklasse</translation>
        </message>
        <message>
            <source>Difference model (DEM − reference)</source>
            <extracomment>dem_compare output difference</extracomment>
            <translation>Differenzmodell (Höhenmodell − Referenz)</translation>
        </message>
        <message>
            <source>Hillshade of the DEM</source>
            <extracomment>dem_compare output hillshade</extracomment>
            <translation>Schummerung des Höhenmodells</translation>
        </message>
        <message>
            <source>Slope of the DEM [°]</source>
            <extracomment>dem_compare output slope</extracomment>
            <translation>Geländeneigung des Höhenmodells [°]</translation>
        </message>
        <message>
            <source>HTML report</source>
            <extracomment>dem_compare output report</extracomment>
            <translation>HTML-Bericht</translation>
        </message>
        <message>
            <source>Statistics as JSON</source>
            <extracomment>dem_compare output json; point_compare output json</extracomment>
            <translation>Statistik als JSON</translation>
        </message>
        <message>
            <source>Statistics as CSV</source>
            <extracomment>dem_compare output csv; point_compare output csv</extracomment>
            <translation>Statistik als CSV</translation>
        </message>
        <message>
            <source>DEM profiles along a line</source>
            <extracomment>dem_profile: name</extracomment>
            <translation>Höhenprofile entlang einer Linie</translation>
        </message>
        <message>
            <source>Samples several DEMs (bilinear) along a line at a constant spacing and writes the table profile.csv (distance, x, y, one height column per DEM) and the plot profile.png. The line is the first line feature of a vector file (any CRS) or a list of coordinates in the first DEM's CRS.</source>
            <extracomment>dem_profile: help</extracomment>
            <translation>Tastet mehrere Höhenmodelle (bilinear) entlang einer Linie in festem Abstand ab und schreibt die Tabelle profile.csv (Distanz, x, y, eine Höhenspalte je Höhenmodell) und das Diagramm profile.png. Die Linie ist das erste Linienobjekt einer Vektordatei (beliebiges KBS) oder eine Koordinatenliste im KBS des ersten Höhenmodells.</translation>
        </message>
        <message>
            <source>DEMs</source>
            <extracomment>dem_profile.dems: description</extracomment>
            <translation>Höhenmodelle</translation>
        </message>
        <message>
            <source>Profile line (vector file)</source>
            <extracomment>dem_profile.line: description</extracomment>
            <translation>Profillinie (Vektordatei)</translation>
        </message>
        <message>
            <source>Its first line feature is the profile; it is transformed to the first DEM's CRS.</source>
            <extracomment>dem_profile.line: help</extracomment>
            <translation>Ihr erstes Linienobjekt ist das Profil; es wird in das KBS des ersten Höhenmodells transformiert.</translation>
        </message>
        <message>
            <source>Profile line as coordinates</source>
            <extracomment>dem_profile.coordinates: description</extracomment>
            <translation>Profillinie als Koordinaten</translation>
        </message>
        <message>
            <source>'x1,y1;x2,y2;…' in the first DEM's CRS (when no line file is given).</source>
            <extracomment>dem_profile.coordinates: help</extracomment>
            <translation>'x1,y1;x2,y2;…' im KBS des ersten Höhenmodells (wenn keine Liniendatei angegeben ist).</translation>
        </message>
        <message>
            <source>Sample spacing [m]</source>
            <extracomment>dem_profile.spacing: description</extracomment>
            <translation>Abtastabstand [m]</translation>
        </message>
        <message>
            <source>Default: the finest cell size of the DEMs.</source>
            <extracomment>dem_profile.spacing: help</extracomment>
            <translation>Standard: die kleinste Zellgröße der Höhenmodelle.</translation>
        </message>
        <message>
            <source>Profile table (CSV)</source>
            <extracomment>dem_profile output csv</extracomment>
            <translation>Profiltabelle (CSV)</translation>
        </message>
        <message>
            <source>Profile plot (PNG)</source>
            <extracomment>dem_profile output png</extracomment>
            <translation>Profildiagramm (PNG)</translation>
        </message>
        <message>
            <source>Line length [m]</source>
            <extracomment>dem_profile output length</extracomment>
            <translation>Linienlänge [m]</translation>
        </message>
        <message>
            <source>Number of samples</source>
            <extracomment>dem_profile output samples</extracomment>
            <translation>Anzahl der Abtastpunkte</translation>
        </message>
        <message>
            <source>Compare points with DEM</source>
            <extracomment>point_compare: name</extracomment>
            <translation>Punkte mit Höhenmodell vergleichen</translation>
        </message>
        <message>
            <source>Compares points (check points or matched points) with a DEM: Δz = DEM − point, the DEM interpolated bilinearly. Reads XYZ text ('x y z' or 'id x y z', whitespace or commas, '#' comments), CSV with a header (columns x, y, z by name) or a GeoPackage of 3-D points (or with a height field). Writes residuals.csv (points outside the DEM are listed as such) and the same statistics as the DEM comparison.</source>
            <extracomment>point_compare: help</extracomment>
            <translation>Vergleicht Punkte (Kontrollpunkte oder Zuordnungspunkte) mit einem Höhenmodell: Δz = Höhenmodell − Punkt, das Höhenmodell bilinear interpoliert. Liest XYZ-Text ('x y z' oder 'id x y z', Leerraum oder Kommas, '#'-Kommentare), CSV mit Kopfzeile (Spalten x, y, z nach Namen) oder ein GeoPackage mit 3D-Punkten (oder mit einem Höhenfeld). Schreibt residuals.csv (Punkte außerhalb des Höhenmodells werden als solche aufgeführt) und dieselbe Statistik wie der Höhenmodellvergleich.</translation>
        </message>
        <message>
            <source>Points (XYZ text, CSV or GeoPackage)</source>
            <extracomment>interpolate_dem.points: description; point_compare.points: description</extracomment>
            <translation>Punkte (XYZ-Text, CSV oder GeoPackage)</translation>
        </message>
        <message>
            <source>Statistics of Δz [m]</source>
            <extracomment>point_compare output stats</extracomment>
            <translation>Statistik von Δz [m]</translation>
        </message>
        <message>
            <source>Points read</source>
            <extracomment>interpolate_dem output points; point_compare output points</extracomment>
            <translation>Gelesene Punkte</translation>
        </message>
        <message>
            <source>Points on the DEM</source>
            <extracomment>point_compare output used</extracomment>
            <translation>Punkte auf dem Höhenmodell</translation>
        </message>
        <message>
            <source>Points outside the DEM</source>
            <extracomment>point_compare output outside</extracomment>
            <translation>Punkte außerhalb des Höhenmodells</translation>
        </message>
        <message>
            <source>Residual table (CSV)</source>
            <extracomment>point_compare output residuals</extracomment>
            <translation>Residuentabelle (CSV)</translation>
        </message>
        <message>
            <source>Stereo disparity (dense matching)</source>
            <extracomment>stereo_disparity: name</extracomment>
            <translation>Stereo-Disparität (dichte Zuordnung)</translation>
        </message>
        <message>
            <source>Matching</source>
            <extracomment>match_model: group; stereo_disparity: group</extracomment>
            <translation>Bildzuordnung</translation>
        </message>
        <message>
            <source>Dense matching of an epipolar (rectified) image pair, e.g. left.tif and right.tif of 'Epipolar pair': a disparity d = x_left − x_right for every pixel of the left image, by semi-global matching with radiometric normalisation, left–right check, sub-pixel refinement, speckle removal and filling of narrow gaps along the epipolar lines. Alpha bands and nodata are honoured. Works in tiles, so large images fit in memory.</source>
            <extracomment>stereo_disparity: help</extracomment>
            <translation>Dichte Zuordnung eines Epipolarbildpaars (Normalfall), z. B. left.tif und right.tif aus „Epipolarbildpaar“: eine Disparität d = x_links − x_rechts für jedes Pixel des linken Bildes, durch Semi-Global Matching mit radiometrischer Normierung, Links-rechts-Prüfung, Subpixel-Verfeinerung, Entfernen kleiner Störflecken und Füllen schmaler Lücken entlang der Epipolarlinien. Alphakanäle und NoData werden beachtet. Arbeitet in Kacheln, sodass auch große Bilder in den Speicher passen.</translation>
        </message>
        <message>
            <source>Minimum disparity [px]</source>
            <extracomment>stereo_disparity.min_disparity: description</extracomment>
            <translation>Minimale Disparität [px]</translation>
        </message>
        <message>
            <source>Smallest x_left − x_right searched; may be negative.</source>
            <extracomment>stereo_disparity.min_disparity: help</extracomment>
            <translation>Kleinstes gesuchtes x_links − x_rechts; darf negativ sein.</translation>
        </message>
        <message>
            <source>Maximum disparity [px]</source>
            <extracomment>stereo_disparity.max_disparity: description</extracomment>
            <translation>Maximale Disparität [px]</translation>
        </message>
        <message>
            <source>Largest x_left − x_right searched.</source>
            <extracomment>stereo_disparity.max_disparity: help</extracomment>
            <translation>Größtes gesuchtes x_links − x_rechts.</translation>
        </message>
        <message>
            <source>Method</source>
            <extracomment>match_model.method: description; stereo_disparity.method: description</extracomment>
            <translation>Verfahren</translation>
        </message>
        <message>
            <source>sgm: 8-path semi-global matching with radiometric normalisation, left–right check and gap filling; opencv_sgbm: plain OpenCV StereoSGBM for comparison.</source>
            <extracomment>stereo_disparity.method: help</extracomment>
            <translation>sgm: Semi-Global Matching über 8 Pfade mit radiometrischer Normierung, Links-rechts-Prüfung und Lückenfüllung; opencv_sgbm: unverändertes OpenCV StereoSGBM zum Vergleich.</translation>
        </message>
        <message>
            <source>sgm</source>
            <extracomment>stereo_disparity.method: option</extracomment>
            <translation>sgm</translation>
        </message>
        <message>
            <source>opencv_sgbm</source>
            <extracomment>stereo_disparity.method: option</extracomment>
            <translation>opencv_sgbm</translation>
        </message>
        <message>
            <source>Disparity raster</source>
            <extracomment>stereo_disparity output disparity; stereo_disparity.output: description</extracomment>
            <translation>Disparitätsraster</translation>
        </message>
        <message>
            <source>Float32 GeoTIFF in left-image geometry, NaN where no disparity.</source>
            <extracomment>stereo_disparity.output: help</extracomment>
            <translation>Float32-GeoTIFF in der Geometrie des linken Bildes, NaN ohne Disparität.</translation>
        </message>
        <message>
            <source>Block size [px]</source>
            <extracomment>stereo_disparity.block_size: description</extracomment>
            <translation>Blockgröße [px]</translation>
        </message>
        <message>
            <source>Odd side of the matching window.</source>
            <extracomment>stereo_disparity.block_size: help</extracomment>
            <translation>Ungerade Seitenlänge des Korrelationsfensters.</translation>
        </message>
        <message>
            <source>Penalty P1</source>
            <extracomment>stereo_disparity.p1: description</extracomment>
            <translation>Strafterm P1</translation>
        </message>
        <message>
            <source>SGM penalty for 1 px disparity steps. Default: 8 × block size².</source>
            <extracomment>stereo_disparity.p1: help</extracomment>
            <translation>SGM-Strafterm für Disparitätssprünge von 1 px. Standard: 8 × Blockgröße².</translation>
        </message>
        <message>
            <source>Penalty P2</source>
            <extracomment>stereo_disparity.p2: description</extracomment>
            <translation>Strafterm P2</translation>
        </message>
        <message>
            <source>SGM penalty for larger disparity steps. Default: 32 × block size².</source>
            <extracomment>stereo_disparity.p2: help</extracomment>
            <translation>SGM-Strafterm für größere Disparitätssprünge. Standard: 32 × Blockgröße².</translation>
        </message>
        <message>
            <source>Uniqueness [%]</source>
            <extracomment>stereo_disparity.uniqueness: description</extracomment>
            <translation>Eindeutigkeit [%]</translation>
        </message>
        <message>
            <source>Percent by which the best match must beat the second best.</source>
            <extracomment>stereo_disparity.uniqueness: help</extracomment>
            <translation>Prozent, um die die beste Zuordnung besser sein muss als die zweitbeste.</translation>
        </message>
        <message>
            <source>Left–right tolerance [px]</source>
            <extracomment>stereo_disparity.lr_max_diff: description</extracomment>
            <translation>Links-rechts-Toleranz [px]</translation>
        </message>
        <message>
            <source>Largest difference of left and right disparity; negative = no check.</source>
            <extracomment>stereo_disparity.lr_max_diff: help</extracomment>
            <translation>Größter Unterschied zwischen linker und rechter Disparität; negativ = keine Prüfung.</translation>
        </message>
        <message>
            <source>Fill gaps up to [px]</source>
            <extracomment>stereo_disparity.fill_max_width: description</extracomment>
            <translation>Lücken füllen bis [px]</translation>
        </message>
        <message>
            <source>Invalid runs along a row up to this width get the farther (smaller) neighbouring disparity; 0 = no filling.</source>
            <extracomment>stereo_disparity.fill_max_width: help</extracomment>
            <translation>Ungültige Abschnitte einer Zeile bis zu dieser Breite erhalten die entferntere (kleinere) benachbarte Disparität; 0 = nicht füllen.</translation>
        </message>
        <message>
            <source>Memory per tile [MB]</source>
            <extracomment>stereo_disparity.memory_mb: description</extracomment>
            <translation>Speicher je Kachel [MB]</translation>
        </message>
        <message>
            <source>Bounds the memory of the matching; sets the tile size.</source>
            <extracomment>stereo_disparity.memory_mb: help</extracomment>
            <translation>Begrenzt den Speicherbedarf der Zuordnung; bestimmt die Kachelgröße.</translation>
        </message>
        <message>
            <source>Share of pixels with a disparity</source>
            <extracomment>stereo_disparity output valid_share</extracomment>
            <translation>Anteil der Pixel mit Disparität</translation>
        </message>
        <message>
            <source>Smallest disparity [px]</source>
            <extracomment>stereo_disparity output min</extracomment>
            <translation>Kleinste Disparität [px]</translation>
        </message>
        <message>
            <source>Largest disparity [px]</source>
            <extracomment>stereo_disparity output max</extracomment>
            <translation>Größte Disparität [px]</translation>
        </message>
        <message>
            <source>Match stereo model (DSM)</source>
            <extracomment>match_model: name</extracomment>
            <translation>Stereomodell zuordnen (DOM)</translation>
        </message>
        <message>
            <source>Matches the two images of a stereo model and grids the points to a DSM. dense: epipolar resampling, semi-global matching with left–right check, triangulation of every valid disparity, median per DSM cell, interpolation of small gaps that does not cross breaklines; exclusion areas and boundaries of edits.gpkg are honoured (NaN). Writes dsm.tif (float32, NaN = no height), count.tif (points per cell) and report.json (points, coverage, valid disparities, timings).</source>
            <extracomment>match_model: help</extracomment>
            <translation>Ordnet die beiden Bilder eines Stereomodells zu und rastert die Punkte zu einem DOM. dense: Epipolarumbildung, Semi-Global Matching mit Links–Rechts-Prüfung, Vorwärtsschnitt jeder gültigen Disparität, Median je DOM-Zelle, Interpolation kleiner Lücken, die Bruchkanten nicht überquert; Ausschlussflächen und Begrenzungen aus edits.gpkg werden beachtet (NaN). Schreibt dsm.tif (float32, NaN = keine Höhe), count.tif (Punkte je Zelle) und report.json (Punkte, Abdeckung, gültige Disparitäten, Zeiten).</translation>
        </message>
        <message>
            <source>dense: semi-global matching of every pixel on the epipolar pair.</source>
            <extracomment>match_model.method: help</extracomment>
            <translation>dense: Semi-Global Matching jedes Pixels im Epipolarpaar.</translation>
        </message>
        <message>
            <source>dense</source>
            <extracomment>match_model.method: option</extracomment>
            <translation>dense</translation>
        </message>
        <message>
            <source>Default: &lt;project&gt;/products/dsm/&lt;model&gt;/.</source>
            <extracomment>match_model.output: help</extracomment>
            <translation>Standard: &lt;Projekt&gt;/products/dsm/&lt;Modell&gt;/.</translation>
        </message>
        <message>
            <source>DSM spacing [m]</source>
            <extracomment>match_model.spacing: description</extracomment>
            <translation>DOM-Gitterweite [m]</translation>
        </message>
        <message>
            <source>Default: 1 × the model's ground sample distance.</source>
            <extracomment>match_model.spacing: help</extracomment>
            <translation>Standard: 1 × Bodenpixelgröße des Modells.</translation>
        </message>
        <message>
            <source>Lowest height [m]</source>
            <extracomment>match_model.min_height: description</extracomment>
            <translation>Niedrigste Höhe [m]</translation>
        </message>
        <message>
            <source>Lowest terrain/object height searched. Default: terrain height − 0.3 × flying height above ground.</source>
            <extracomment>match_model.min_height: help</extracomment>
            <translation>Niedrigste gesuchte Gelände-/Objekthöhe. Standard: Geländehöhe − 0,3 × Flughöhe über Grund.</translation>
        </message>
        <message>
            <source>Highest height [m]</source>
            <extracomment>match_model.max_height: description</extracomment>
            <translation>Höchste Höhe [m]</translation>
        </message>
        <message>
            <source>Highest terrain/object height searched. Default: terrain height + 0.3 × flying height above ground.</source>
            <extracomment>match_model.max_height: help</extracomment>
            <translation>Höchste gesuchte Gelände-/Objekthöhe. Standard: Geländehöhe + 0,3 × Flughöhe über Grund.</translation>
        </message>
        <message>
            <source>Interpolate gaps up to [m]</source>
            <extracomment>interpolate_dem.max_gap: description; match_model.max_gap: description</extracomment>
            <translation>Lücken interpolieren bis [m]</translation>
        </message>
        <message>
            <source>Larger gaps stay empty (NaN). Default: 10 × spacing.</source>
            <extracomment>match_model.max_gap: help</extracomment>
            <translation>Größere Lücken bleiben leer (NaN). Standard: 10 × Gitterweite.</translation>
        </message>
        <message>
            <source>DSM</source>
            <extracomment>match_model output dsm</extracomment>
            <translation>DOM</translation>
        </message>
        <message>
            <source>Points per cell</source>
            <extracomment>interpolate_dem output count; match_model output count</extracomment>
            <translation>Punkte je Zelle</translation>
        </message>
        <message>
            <source>Points (not written yet)</source>
            <extracomment>match_model output points</extracomment>
            <translation>Punkte (noch nicht geschrieben)</translation>
        </message>
        <message>
            <source>Report (JSON)</source>
            <extracomment>match_model output report</extracomment>
            <translation>Bericht (JSON)</translation>
        </message>
        <message>
            <source>Metrics</source>
            <extracomment>match_model output metrics</extracomment>
            <translation>Kennzahlen</translation>
        </message>
        <message>
            <source>Merge DSMs</source>
            <extracomment>dsm_merge: name</extracomment>
            <translation>DOMs zusammenführen</translation>
        </message>
        <message>
            <source>Surfaces</source>
            <extracomment>dsm_merge: group; interpolate_dem: group</extracomment>
            <translation>Oberflächen</translation>
        </message>
        <message>
            <source>Merges model DSMs into one DSM on a common grid: the union of their extents at the finest input cell size (or at the given spacing), in the CRS of the first input; inputs with another grid or CRS are resampled bilinearly, window by window. Modes: median or mean of the heights per cell; best_sigma takes the height of the input with the smallest σ, where σ is a second band of the input or a raster &lt;name&gt;_sigma.tif or sigma.tif beside it — inputs without σ are used only where no input with σ has a height (as their median), so without any σ best_sigma is the median. Writes the DSM, &lt;name&gt;_count.tif (inputs per cell) and the seam statistics of every overlapping pair (Δh = a − b: count, mean, median, std, RMS, NMAD) as &lt;name&gt;_seams.json and .csv.</source>
            <extracomment>dsm_merge: help</extracomment>
            <translation>Führt Modell-DOMs auf einem gemeinsamen Raster zu einem DOM zusammen: die Vereinigung ihrer Ausdehnungen mit der feinsten Zellgröße der Eingaben (oder der angegebenen Zellgröße), im KBS der ersten Eingabe; Eingaben mit anderem Raster oder KBS werden fensterweise bilinear umgetastet. Modi: Median oder Mittel der Höhen je Zelle; best_sigma nimmt die Höhe der Eingabe mit dem kleinsten σ, wobei σ ein zweiter Kanal der Eingabe oder ein Raster &lt;Name&gt;_sigma.tif oder sigma.tif daneben ist — Eingaben ohne σ werden nur dort verwendet, wo keine Eingabe mit σ eine Höhe hat (als ihr Median), ohne jedes σ ist best_sigma also der Median. Schreibt das DOM, &lt;Name&gt;_count.tif (Eingaben je Zelle) und die Nahtstatistik jedes überlappenden Paars (Δh = a − b: Anzahl, Mittel, Median, Standardabweichung, RMS, NMAD) als &lt;Name&gt;_seams.json und .csv.</translation>
        </message>
        <message>
            <source>Input DSMs</source>
            <extracomment>dsm_merge.inputs: description</extracomment>
            <translation>Eingabe-DOMs</translation>
        </message>
        <message>
            <source>Model DSMs (NaN or nodata = no height), any extents, grids and CRSs.</source>
            <extracomment>dsm_merge.inputs: help</extracomment>
            <translation>Modell-DOMs (NaN oder NoData = keine Höhe), beliebige Ausdehnungen, Raster und KBS.</translation>
        </message>
        <message>
            <source>Merged DSM</source>
            <extracomment>dsm_merge output dsm; dsm_merge.output: description</extracomment>
            <translation>Zusammengeführtes DOM</translation>
        </message>
        <message>
            <source>Float32 GeoTIFF, NaN where no input has a height.</source>
            <extracomment>dsm_merge.output: help</extracomment>
            <translation>Float32-GeoTIFF, NaN, wo keine Eingabe eine Höhe hat.</translation>
        </message>
        <message>
            <source>Merge mode</source>
            <extracomment>dsm_merge.mode: description</extracomment>
            <translation>Zusammenführungsmodus</translation>
        </message>
        <message>
            <source>median: robust against one wrong model where three or more overlap; mean: average; best_sigma: the height with the smallest σ.</source>
            <extracomment>dsm_merge.mode: help</extracomment>
            <translation>median: robust gegen ein falsches Modell, wo sich drei oder mehr überlappen; mean: Mittelwert; best_sigma: die Höhe mit dem kleinsten σ.</translation>
        </message>
        <message>
            <source>median</source>
            <extracomment>dsm_merge.mode: option</extracomment>
            <translation>Median</translation>
        </message>
        <message>
            <source>mean</source>
            <extracomment>dsm_merge.mode: option</extracomment>
            <translation>Mittelwert</translation>
        </message>
        <message>
            <source>best_sigma</source>
            <extracomment>dsm_merge.mode: option</extracomment>
            <translation>bestes σ</translation>
        </message>
        <message>
            <source>Cell size [m]</source>
            <extracomment>dsm_merge.spacing: description; interpolate_dem.spacing: description</extracomment>
            <translation>Zellgröße [m]</translation>
        </message>
        <message>
            <source>Default: the finest cell size of the inputs.</source>
            <extracomment>dsm_merge.spacing: help</extracomment>
            <translation>Standard: die feinste Zellgröße der Eingaben.</translation>
        </message>
        <message>
            <source>Inputs per cell</source>
            <extracomment>dsm_merge output count</extracomment>
            <translation>Eingaben je Zelle</translation>
        </message>
        <message>
            <source>Seam statistics per overlapping pair</source>
            <extracomment>dsm_merge output seams</extracomment>
            <translation>Nahtstatistik je überlappendem Paar</translation>
        </message>
        <message>
            <source>Seam statistics (JSON)</source>
            <extracomment>dsm_merge output report</extracomment>
            <translation>Nahtstatistik (JSON)</translation>
        </message>
        <message>
            <source>Seam statistics (CSV)</source>
            <extracomment>dsm_merge output csv</extracomment>
            <translation>Nahtstatistik (CSV)</translation>
        </message>
        <message>
            <source>Share of cells with a height</source>
            <extracomment>dsm_merge output coverage; interpolate_dem output coverage</extracomment>
            <translation>Anteil der Zellen mit Höhe</translation>
        </message>
        <message>
            <source>Interpolate DEM from points</source>
            <extracomment>interpolate_dem: name</extracomment>
            <translation>DHM aus Punkten interpolieren</translation>
        </message>
        <message>
            <source>Grids points (XYZ text, CSV with x, y, z columns, or 3-D points in a GeoPackage) to a DEM: the median of the points in each cell, then membrane interpolation of the empty cells that does not cross breaklines (3-D breaklines give their own heights). Exclusion areas are NaN, and so is everything outside the boundary polygons. Breaklines, exclusion areas and boundaries come from the project's edits.gpkg and/or from the given vector files. Writes the DEM and &lt;name&gt;_count.tif (points per cell).</source>
            <extracomment>interpolate_dem: help</extracomment>
            <translation>Rastert Punkte (XYZ-Text, CSV mit Spalten x, y, z oder 3-D-Punkte in einem GeoPackage) zu einem DHM: der Median der Punkte jeder Zelle, dann Membran-Interpolation der leeren Zellen, die Bruchkanten nicht überquert (3-D-Bruchkanten liefern ihre eigenen Höhen). Ausschlussflächen sind NaN, ebenso alles außerhalb der Begrenzungspolygone. Bruchkanten, Ausschlussflächen und Begrenzungen kommen aus der edits.gpkg des Projekts und/oder aus den angegebenen Vektordateien. Schreibt das DHM und &lt;Name&gt;_count.tif (Punkte je Zelle).</translation>
        </message>
        <message>
            <source>DEM</source>
            <extracomment>interpolate_dem output dem; interpolate_dem.output: description</extracomment>
            <translation>DHM</translation>
        </message>
        <message>
            <source>Float32 GeoTIFF, NaN where there is no height.</source>
            <extracomment>interpolate_dem.output: help</extracomment>
            <translation>Float32-GeoTIFF, NaN, wo keine Höhe vorliegt.</translation>
        </message>
        <message>
            <source>CRS</source>
            <extracomment>interpolate_dem.crs: description</extracomment>
            <translation>KBS</translation>
        </message>
        <message>
            <source>CRS of the DEM and of text points. Default: the project's, else the points' own.</source>
            <extracomment>interpolate_dem.crs: help</extracomment>
            <translation>KBS des DHM und von Textpunkten. Standard: das des Projekts, sonst das der Punkte.</translation>
        </message>
        <message>
            <source>Project (edits.gpkg)</source>
            <extracomment>interpolate_dem.project: description</extracomment>
            <translation>Projekt (edits.gpkg)</translation>
        </message>
        <message>
            <source>Its breaklines, exclusion areas and boundaries are honoured.</source>
            <extracomment>interpolate_dem.project: help</extracomment>
            <translation>Seine Bruchkanten, Ausschlussflächen und Begrenzungen werden beachtet.</translation>
        </message>
        <message>
            <source>Breaklines (vector file)</source>
            <extracomment>interpolate_dem.breaklines: description</extracomment>
            <translation>Bruchkanten (Vektordatei)</translation>
        </message>
        <message>
            <source>(3-D) lines the interpolation does not cross.</source>
            <extracomment>interpolate_dem.breaklines: help</extracomment>
            <translation>(3-D-)Linien, die die Interpolation nicht überquert.</translation>
        </message>
        <message>
            <source>Exclusion areas (vector file)</source>
            <extracomment>interpolate_dem.exclusions: description</extracomment>
            <translation>Ausschlussflächen (Vektordatei)</translation>
        </message>
        <message>
            <source>Polygons that stay empty (NaN).</source>
            <extracomment>interpolate_dem.exclusions: help</extracomment>
            <translation>Polygone, die leer bleiben (NaN).</translation>
        </message>
        <message>
            <source>Boundary (vector file)</source>
            <extracomment>interpolate_dem.boundary: description</extracomment>
            <translation>Begrenzung (Vektordatei)</translation>
        </message>
        <message>
            <source>Polygons of the measuring area; NaN outside.</source>
            <extracomment>interpolate_dem.boundary: help</extracomment>
            <translation>Polygone des Messgebiets; außerhalb NaN.</translation>
        </message>
        <message>
            <source>Larger gaps stay empty (NaN). Default: every gap is interpolated.</source>
            <extracomment>interpolate_dem.max_gap: help</extracomment>
            <translation>Größere Lücken bleiben leer (NaN). Standard: jede Lücke wird interpoliert.</translation>
        </message>
        <message>
            <source>Points in the grid</source>
            <extracomment>interpolate_dem output used</extracomment>
            <translation>Punkte im Raster</translation>
        </message>
        <message>
            <source>Interpolated cells</source>
            <extracomment>interpolate_dem output filled</extracomment>
            <translation>Interpolierte Zellen</translation>
        </message>
        <message>
            <source>PhotoDEM toolbox</source>
            <extracomment>plugin/app/main_window.py:37</extracomment>
            <translation>PhotoDEM-Werkzeugkasten</translation>
        </message>
        <message>
            <source>Search algorithms …</source>
            <extracomment>plugin/app/main_window.py:44</extracomment>
            <translation>Algorithmen suchen …</translation>
        </message>
        <message>
            <source>Choose an algorithm on the left.</source>
            <extracomment>plugin/app/main_window.py:98</extracomment>
            <translation>Links einen Algorithmus wählen.</translation>
        </message>
        <message>
            <source>&amp;File</source>
            <extracomment>plugin/app/main_window.py:108</extracomment>
            <translation>&amp;Datei</translation>
        </message>
        <message>
            <source>&amp;Quit</source>
            <extracomment>plugin/app/main_window.py:109</extracomment>
            <translation>&amp;Beenden</translation>
        </message>
        <message>
            <source>&amp;Help</source>
            <extracomment>plugin/app/main_window.py:112</extracomment>
            <translation>&amp;Hilfe</translation>
        </message>
        <message>
            <source>&amp;About PhotoDEM</source>
            <extracomment>plugin/app/main_window.py:113</extracomment>
            <translation>&amp;Über PhotoDEM</translation>
        </message>
        <message>
            <source>{0} finished.</source>
            <extracomment>plugin/app/main_window.py:203</extracomment>
            <translation>{0} ist fertig.</translation>
        </message>
        <message>
            <source>{0} failed.</source>
            <extracomment>plugin/app/main_window.py:203</extracomment>
            <translation>{0} ist fehlgeschlagen.</translation>
        </message>
        <message>
            <source>{0} was cancelled.</source>
            <extracomment>plugin/app/main_window.py:204</extracomment>
            <translation>{0} wurde abgebrochen.</translation>
        </message>
        <message>
            <source>About PhotoDEM</source>
            <extracomment>plugin/app/main_window.py:218</extracomment>
            <translation>Über PhotoDEM</translation>
        </message>
        <message>
            <source>PhotoDEM: aerial photogrammetry — DSMs by image matching, DTMs by filtering, orthophoto mosaics and automatic georeferencing.</source>
            <extracomment>plugin/app/main_window.py:219</extracomment>
            <translation>PhotoDEM: Luftbildphotogrammetrie — Oberflächenmodelle durch Bildzuordnung, Geländemodelle durch Filterung, Orthophotomosaike und automatische Georeferenzierung.</translation>
        </message>
        <message>
            <source>Other</source>
            <extracomment>plugin/app/main_window.py:123</extracomment>
            <translation>Sonstiges</translation>
        </message>
        <message>
            <source>PhotoDEM</source>
            <extracomment>plugin/app/main_window.py:208</extracomment>
            <translation>PhotoDEM</translation>
        </message>
        <message>
            <source>Running {0} …</source>
            <extracomment>plugin/app/main_window.py:196; plugin/widgets/run_panel.py:101</extracomment>
            <translation>{0} läuft …</translation>
        </message>
        <message>
            <source>PhotoDEM needs Python packages that QGIS cannot find: {0}. Debian/Ubuntu: sudo apt install {1}; Windows: install them with the OSGeo4W installer.</source>
            <extracomment>plugin/qgis/plugin.py:43</extracomment>
            <translation>PhotoDEM benötigt Python-Pakete, die QGIS nicht findet: {0}. Debian/Ubuntu: sudo apt install {1}; Windows: mit dem OSGeo4W-Installer installieren.</translation>
        </message>
        <message>
            <source>PhotoDEM algorithms</source>
            <extracomment>plugin/qgis/plugin.py:92</extracomment>
            <translation>PhotoDEM-Algorithmen</translation>
        </message>
        <message>
            <source>Show the PhotoDEM algorithms in the Processing Toolbox</source>
            <extracomment>plugin/qgis/plugin.py:94</extracomment>
            <translation>Die PhotoDEM-Algorithmen im Verarbeitungswerkzeugkasten zeigen</translation>
        </message>
        <message>
            <source>PhotoDEM aerial photogrammetry</source>
            <extracomment>plugin/qgis/provider.py:34</extracomment>
            <translation>PhotoDEM Luftbildphotogrammetrie</translation>
        </message>
        <message>
            <source>Browse</source>
            <extracomment>plugin/widgets/parameter_form.py:59</extracomment>
            <translation>Durchsuchen</translation>
        </message>
        <message>
            <source>All files (*)</source>
            <extracomment>plugin/widgets/parameter_form.py:76; plugin/widgets/parameter_form.py:78</extracomment>
            <translation>Alle Dateien (*)</translation>
        </message>
        <message>
            <source>Supported files</source>
            <extracomment>plugin/widgets/parameter_form.py:78</extracomment>
            <translation>Unterstützte Dateien</translation>
        </message>
        <message>
            <source>Choose a folder</source>
            <extracomment>plugin/widgets/parameter_form.py:84</extracomment>
            <translation>Ordner wählen</translation>
        </message>
        <message>
            <source>project folder (with project.toml)</source>
            <extracomment>plugin/widgets/parameter_form.py:128</extracomment>
            <translation>Projektordner (mit project.toml)</translation>
        </message>
        <message>
            <source>optional</source>
            <extracomment>plugin/widgets/parameter_form.py:159; plugin/widgets/parameter_form.py:202; plugin/widgets/parameter_form.py:292</extracomment>
            <translation>optional</translation>
        </message>
        <message>
            <source>choose a project first</source>
            <extracomment>plugin/widgets/parameter_form.py:192</extracomment>
            <translation>zuerst ein Projekt wählen</translation>
        </message>
        <message>
            <source>image name</source>
            <extracomment>plugin/widgets/parameter_form.py:192</extracomment>
            <translation>Bildname</translation>
        </message>
        <message>
            <source>required</source>
            <extracomment>plugin/widgets/parameter_form.py:292</extracomment>
            <translation>erforderlich</translation>
        </message>
        <message>
            <source>several files, separated by commas</source>
            <extracomment>plugin/widgets/parameter_form.py:130</extracomment>
            <translation>mehrere Dateien, durch Kommas getrennt</translation>
        </message>
        <message>
            <source>e.g. EPSG:25832</source>
            <extracomment>plugin/widgets/parameter_form.py:200</extracomment>
            <translation>z. B. EPSG:25832</translation>
        </message>
        <message>
            <source>xmin,ymin,xmax,ymax</source>
            <extracomment>plugin/widgets/parameter_form.py:201</extracomment>
            <translation>xmin,ymin,xmax,ymax</translation>
        </message>
        <message>
            <source>type a name</source>
            <extracomment>plugin/widgets/parameter_form.py:347</extracomment>
            <translation>Namen eingeben</translation>
        </message>
        <message>
            <source>no project found</source>
            <extracomment>plugin/widgets/parameter_form.py:347</extracomment>
            <translation>kein Projekt gefunden</translation>
        </message>
        <message>
            <source>Save as</source>
            <extracomment>plugin/widgets/parameter_form.py:86</extracomment>
            <translation>Speichern unter</translation>
        </message>
        <message>
            <source>Choose files</source>
            <extracomment>plugin/widgets/parameter_form.py:88</extracomment>
            <translation>Dateien wählen</translation>
        </message>
        <message>
            <source>Choose a file</source>
            <extracomment>plugin/widgets/parameter_form.py:91</extracomment>
            <translation>Datei wählen</translation>
        </message>
        <message>
            <source>Run</source>
            <extracomment>plugin/widgets/run_panel.py:39</extracomment>
            <translation>Ausführen</translation>
        </message>
        <message>
            <source>Cancel</source>
            <extracomment>plugin/widgets/run_panel.py:42</extracomment>
            <translation>Abbrechen</translation>
        </message>
        <message>
            <source>The log of the run appears here.</source>
            <extracomment>plugin/widgets/run_panel.py:54</extracomment>
            <translation>Hier erscheint das Protokoll des Laufs.</translation>
        </message>
        <message>
            <source>Log</source>
            <extracomment>plugin/widgets/run_panel.py:64</extracomment>
            <translation>Protokoll</translation>
        </message>
        <message>
            <source>Result</source>
            <extracomment>plugin/widgets/run_panel.py:65</extracomment>
            <translation>Ergebnis</translation>
        </message>
        <message>
            <source>Finished.</source>
            <extracomment>plugin/widgets/run_panel.py:152</extracomment>
            <translation>Fertig.</translation>
        </message>
        <message>
            <source>Output</source>
            <extracomment>plugin/widgets/run_panel.py:59</extracomment>
            <translation>Ausgabe</translation>
        </message>
        <message>
            <source>Value</source>
            <extracomment>plugin/widgets/run_panel.py:59</extracomment>
            <translation>Wert</translation>
        </message>
        <message>
            <source>Cancelling …</source>
            <extracomment>plugin/widgets/run_panel.py:123</extracomment>
            <translation>Wird abgebrochen …</translation>
        </message>
        <message>
            <source>Warning: </source>
            <extracomment>plugin/widgets/run_panel.py:143</extracomment>
            <translation>Warnung: </translation>
        </message>
        <message>
            <source>Error: </source>
            <extracomment>plugin/widgets/run_panel.py:157</extracomment>
            <translation>Fehler: </translation>
        </message>
        <message>
            <source>Unexpected error (please report it):</source>
            <extracomment>plugin/widgets/run_panel.py:159</extracomment>
            <translation>Unerwarteter Fehler (bitte melden):</translation>
        </message>
    </context>
</TS>
