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
            <extracomment>plugin/widgets/batch_dialog.py:141; plugin/widgets/qc_panel.py:128; project_create: group; project_info: group; stereo_models: group</extracomment>
            <translation>Projekt</translation>
        </message>
        <message>
            <source>Creates a PhotoDEM project (project.toml + edits.gpkg) from a folder of images and their orientation: an OPK CSV or text file with the camera YAML (orthority format), orthority's exterior GeoJSON, or an OpenSfM/ODM reconstruction.json (in an ODM project: opensfm/reconstruction.json; its frame is read from ODM's georeferencing files and checked against the GPS positions). The block is validated and its stereo models are detected (overlap ≥ 25 %, B/H 0.2–1.2, in-strip neighbours first).</source>
            <extracomment>project_create: help</extracomment>
            <translation>Legt ein PhotoDEM-Projekt (project.toml + edits.gpkg) aus einem Bildordner und der Orientierung der Bilder an: eine OPK-CSV- oder Textdatei mit der Kamera-YAML (Orthority-Format), die Außenorientierungs-GeoJSON von Orthority oder eine OpenSfM/ODM-reconstruction.json (in einem ODM-Projekt: opensfm/reconstruction.json; ihr Bezugssystem wird aus den Georeferenzierungsdateien von ODM gelesen und gegen die GPS-Positionen geprüft). Der Bildverband wird geprüft und seine Stereomodelle werden bestimmt (Überlappung ≥ 25 %, B/H 0,2–1,2, Nachbarn im selben Streifen zuerst).</translation>
        </message>
        <message>
            <source>Images folder</source>
            <extracomment>project_create.images: description</extracomment>
            <translation>Bildordner</translation>
        </message>
        <message>
            <source>Exterior orientation (OPK CSV/text, GeoJSON or reconstruction.json)</source>
            <extracomment>project_create.exterior: description</extracomment>
            <translation>Äußere Orientierung (OPK-CSV/-Text, GeoJSON oder reconstruction.json)</translation>
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
            <source>Largest tilt without a warning [°]</source>
            <extracomment>project_create.max_tilt: description; project_info.max_tilt: description</extracomment>
            <translation>Größte Neigung ohne Warnung [°]</translation>
        </message>
        <message>
            <source>|omega| or |phi| above this is reported as a warning (30° suits vertical aerial images; drone and oblique frames are tilted more). Only a camera looking up is refused.</source>
            <extracomment>project_create.max_tilt: help; project_info.max_tilt: help</extracomment>
            <translation>|Omega| oder |Phi| darüber wird als Warnung gemeldet (30° passt zu Senkrechtluftbildern; Drohnen- und Schrägaufnahmen sind stärker geneigt). Abgelehnt wird nur eine Kamera, die nach oben blickt.</translation>
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
            <source>Lists a project's CRS, images (position, angles in degrees, whether the file exists), cameras and stereo models (B/H, overlap %, GSD, flying height above ground), and the result of its validation. Validation warnings (tilts above max_tilt, unusual flying heights, images without a stereo partner) and errors are reported; a project with errors (a CRS PROJ does not know, no images, missing image files, a camera looking up…) ends with an error naming the first of them (exit code 2 on the command line).</source>
            <extracomment>project_info: help</extracomment>
            <translation>Listet KBS, Bilder (Position, Winkel in Grad, ob die Datei vorhanden ist), Kameras und Stereomodelle (B/H, Überlappung in %, Bodenauflösung, Flughöhe über Grund) eines Projekts sowie das Ergebnis seiner Prüfung auf. Warnungen (Neigungen über max_tilt, ungewöhnliche Flughöhen, Bilder ohne Stereopartner) und Fehler der Prüfung werden gemeldet; ein Projekt mit Fehlern (ein KBS, das PROJ nicht kennt, keine Bilder, fehlende Bilddateien, eine Kamera, die nach oben blickt …) endet mit einem Fehler, der den ersten davon nennt (Exit-Code 2 auf der Kommandozeile).</translation>
        </message>
        <message>
            <source>Project name</source>
            <extracomment>project_info output name</extracomment>
            <translation>Projektname</translation>
        </message>
        <message>
            <source>Images</source>
            <extracomment>project_info output images; refine_object_space.images: description</extracomment>
            <translation>Bilder</translation>
        </message>
        <message>
            <source>Cameras</source>
            <extracomment>project_info output cameras</extracomment>
            <translation>Kameras</translation>
        </message>
        <message>
            <source>Stereo models</source>
            <extracomment>plugin/app/map_window.py:438; plugin/qgis/workspace.py:254; project_info output models; stereo_models output models; stereo_models: name</extracomment>
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
            <source>Generates a deterministic synthetic aerial block: terrain (gentle, dunes or steep), an embankment and a ditch with breaklines, buildings, trees and a forest patch, textured ground with bright check-point discs, frame images in two or more strips (60 % forward, 30 % side overlap; aerial: one strip of three windowed film frames) rendered by ray casting against the true DSM. Writes a complete project (project.toml, images, edits.gpkg, in-strip stereo models) and the ground truth (DTM, DSM, land cover, building footprints, 3-D breaklines, check points) below truth/. The same seed always gives the same block.</source>
            <extracomment>synthetic_block: help</extracomment>
            <translation>Erzeugt einen deterministischen synthetischen Bildflug: Gelände (flach, Dünen oder steil), einen Damm und einen Graben mit Bruchkanten, Gebäude, Bäume und ein Waldstück, texturierten Boden mit hellen Kontrollpunktscheiben sowie Reihenmessbilder in zwei oder mehr Streifen (60 % Längs-, 30 % Querüberdeckung; Luftbild: ein Streifen aus drei Filmbildern, von denen je ein Ausschnitt berechnet wird), gerendert durch Strahlverfolgung gegen das wahre Oberflächenmodell. Schreibt ein vollständiges Projekt (project.toml, Bilder, edits.gpkg, Stereomodelle im Streifen) und die Referenzdaten (Geländemodell, Oberflächenmodell, Landbedeckung, Gebäudegrundrisse, 3D-Bruchkanten, Kontrollpunkte) unter truth/. Derselbe Startwert ergibt immer denselben Bildverband.</translation>
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
            <source>tiny: 224×288 px images (tests); small: 704×1000 px (demo); medium: 1408×2000 px; large: 2400×3400 px (≈ 8 Mpx); aerial: three wide-angle film frames in one strip (11500 px, c = 153 mm, B/H 0.6, base 4600 px, H ≈ 1150 m) of which a 1024×1024 px window over the common ground patch is rendered — for height accuracy in ‰ of H; drone: six 768×576 px frames of a drone camera flown ≈ 70 m above ground, tilted 0–35° in varying directions towards a common patch (convergent pairs, GSD 10 cm at nadir).</source>
            <extracomment>synthetic_block.size: help</extracomment>
            <translation>winzig: Bilder mit 224×288 px (Tests); klein: 704×1000 px (Demo); mittel: 1408×2000 px; groß: 2400×3400 px (≈ 8 Mpx); Luftbild: drei Weitwinkel-Filmbilder in einem Streifen (11500 px, c = 153 mm, B/H 0,6, Basis 4600 px, H ≈ 1150 m), von denen ein Fenster von 1024×1024 px über dem gemeinsam abgebildeten Geländeausschnitt gerendert wird — für die Höhengenauigkeit in ‰ von H; Drohne: sechs Bilder von 768×576 px einer Drohnenkamera, ≈ 70 m über Grund geflogen, 0–35° in wechselnde Richtungen zu einem gemeinsamen Ausschnitt geneigt (konvergente Paare, GSD 10 cm im Nadir).</translation>
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
            <source>aerial</source>
            <extracomment>synthetic_block.size: option</extracomment>
            <translation>Luftbild</translation>
        </message>
        <message>
            <source>drone</source>
            <extracomment>synthetic_block.size: option</extracomment>
            <translation>Drohne</translation>
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
            <extracomment>filter_linear_prediction.preset: option; filter_lowpass.preset: option; synthetic_block.terrain: option</extracomment>
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
            <source>Mean model base in pixels B/GSD (σZ/H = σpx/base_px)</source>
            <extracomment>synthetic_block output base_px</extracomment>
            <translation>Mittlere Modellbasis in Pixeln B/GSD (σZ/H = σpx/base_px)</translation>
        </message>
        <message>
            <source>Mean base-to-height ratio B/H of the models</source>
            <extracomment>synthetic_block output b_h</extracomment>
            <translation>Mittleres Basis-Höhen-Verhältnis B/H der Modelle</translation>
        </message>
        <message>
            <source>Epipolar pair</source>
            <extracomment>epipolar_pair: name; plugin/app/model_menu.py:107; plugin/qgis/model_actions.py:128; plugin/widgets/batch_dialog.py:147; plugin/widgets/batch_dialog.py:170</extracomment>
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
            <extracomment>epipolar_pair.project: description; match_model.project: description; mosaic.project: description; ortho_displacement.project: description; orthorectify.project: description; refine_object_space.project: description</extracomment>
            <translation>Projektordner oder project.toml</translation>
        </message>
        <message>
            <source>Stereo model</source>
            <extracomment>epipolar_pair.model: description; match_model.model: description; plugin/qgis/model_actions.py:258</extracomment>
            <translation>Stereomodell</translation>
        </message>
        <message>
            <source>Output folder</source>
            <extracomment>dem_compare.output: description; dem_profile.output: description; epipolar_pair output folder; epipolar_pair.output: description; filter_evaluate.output: description; filter_linear_prediction.output: description; filter_lowpass.output: description; georeference_polygons.output: description; match_mo</extracomment>
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
            <source>Compares a DEM (DSM or DTM) with a reference DEM on their common area; the reference may have another grid, extent or CRS (the DEM is resampled onto it). Optionally co-registers the DEM first (horizontal shift and vertical bias after Nuth &amp; Kääb, estimated on stable terrain). Writes the difference model Δh = DEM − reference (with a QGIS style), a hillshade and a slope raster of the DEM, statistics (mean, median, std, RMS, NMAD, quantiles of |Δh|, 0.5 m classes) overall, per class and per slope class, in m and in ‰ of the flying height, and an HTML report with plots. With the reference's terrain model (DTM) the cells are also classed into object interior, object edge, open terrain and other by their height above the DTM; with classes or a DTM the completeness per class is reported too: the share of the reference cells the DEM measures, and the shares within ±0.5 m and ±1 m (empty cells count as misses).</source>
            <extracomment>dem_compare: help</extracomment>
            <translation>Vergleicht ein Höhenmodell (DOM oder DGM) im gemeinsamen Gebiet mit einem Referenzmodell; das Referenzmodell darf ein anderes Raster, eine andere Ausdehnung oder ein anderes KBS haben (das Höhenmodell wird darauf umgerechnet). Optional wird das Höhenmodell vorher koregistriert (Lageverschiebung und Höhenversatz nach Nuth &amp; Kääb, geschätzt auf stabilem Gelände). Schreibt das Differenzmodell Δh = Höhenmodell − Referenz (mit QGIS-Stil), eine Schummerung und ein Neigungsraster des Höhenmodells, Statistiken (Mittel, Median, Standardabweichung, RMS, NMAD, Quantile von |Δh|, 0,5-m-Klassen) insgesamt, je Klasse und je Neigungsklasse, in m und in ‰ der Flughöhe, sowie einen HTML-Bericht mit Diagrammen. Mit dem Geländemodell (DGM) der Referenz werden die Zellen außerdem nach ihrer Höhe über dem DGM in Objektinneres, Objektrand, offenes Gelände und Sonstiges eingeteilt; mit Klassen oder einem DGM wird auch die Vollständigkeit je Klasse angegeben: der Anteil der Referenzzellen, die das Höhenmodell misst, und die Anteile innerhalb ±0,5 m und ±1 m (leere Zellen zählen als Fehlschläge).</translation>
        </message>
        <message>
            <source>DEM to check</source>
            <extracomment>dem_compare.dem: description; plugin/widgets/qc_panel.py:129; point_compare.dem: description</extracomment>
            <translation>Zu prüfendes Höhenmodell</translation>
        </message>
        <message>
            <source>Reference DEM</source>
            <extracomment>dem_compare.reference: description; plugin/widgets/qc_panel.py:131</extracomment>
            <translation>Referenzmodell</translation>
        </message>
        <message>
            <source>Receives difference.tif (+ .qml style), hillshade.tif, slope.tif, report.html, stats.json and stats.csv; with classes or a DTM also completeness.csv.</source>
            <extracomment>dem_compare.output: help</extracomment>
            <translation>Erhält difference.tif (+ .qml-Stil), hillshade.tif, slope.tif, report.html, stats.json und stats.csv; mit Klassen oder einem DGM auch completeness.csv.</translation>
        </message>
        <message>
            <source>Co-register before comparing</source>
            <extracomment>dem_compare.coregister: description; plugin/widgets/qc_panel.py:169</extracomment>
            <translation>Vor dem Vergleich koregistrieren</translation>
        </message>
        <message>
            <source>Estimate and remove a horizontal shift and a vertical bias (Nuth &amp; Kääb) on stable terrain first.</source>
            <extracomment>dem_compare.coregister: help</extracomment>
            <translation>Zuerst Lageverschiebung und Höhenversatz (Nuth &amp; Kääb) auf stabilem Gelände schätzen und entfernen.</translation>
        </message>
        <message>
            <source>Stable terrain (mask raster or polygons)</source>
            <extracomment>dem_compare.stable: description; plugin/widgets/qc_panel.py:174</extracomment>
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
            <source>Class names (legend of a class raster)</source>
            <extracomment>dem_compare.class_legend: description</extracomment>
            <translation>Klassennamen (Legende eines Klassenrasters)</translation>
        </message>
        <message>
            <source>Names of the codes of a class raster: a table with one 'value,name' per line, or a QGIS style (.qml). Default: the style beside the raster (landcover.qml for landcover.tif), else the codes.</source>
            <extracomment>dem_compare.class_legend: help</extracomment>
            <translation>Namen der Codes eines Klassenrasters: eine Tabelle mit einer Zeile 'Wert,Name' je Klasse oder ein QGIS-Stil (.qml). Vorgabe: der Stil neben dem Raster (landcover.qml zu landcover.tif), sonst die Codes.</translation>
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
            <source>Terrain model (DTM) of the reference</source>
            <extracomment>dem_compare.dtm: description</extracomment>
            <translation>Geländemodell (DGM) der Referenz</translation>
        </message>
        <message>
            <source>When the reference is a DSM: its terrain model. Cells at least the object height above it are objects (buildings, trees); statistics and completeness per object class.</source>
            <extracomment>dem_compare.dtm: help</extracomment>
            <translation>Wenn die Referenz ein DOM ist: ihr Geländemodell. Zellen, die mindestens die Objekthöhe darüber liegen, sind Objekte (Gebäude, Bäume); Statistik und Vollständigkeit je Objektklasse.</translation>
        </message>
        <message>
            <source>Object height [m]</source>
            <extracomment>dem_compare.object_height: description; mosaic.min_height: description</extracomment>
            <translation>Objekthöhe [m]</translation>
        </message>
        <message>
            <source>Height above the DTM from which a reference cell belongs to an object.</source>
            <extracomment>dem_compare.object_height: help</extracomment>
            <translation>Höhe über dem DGM, ab der eine Referenzzelle zu einem Objekt gehört.</translation>
        </message>
        <message>
            <source>Tile size [cells]</source>
            <extracomment>dem_compare.tile: description; dsm_merge.tile: description; filter_linear_prediction.tile: description; filter_lowpass.tile: description; mosaic.tile: description; refine_object_space.tile: description</extracomment>
            <translation>Kachelgröße [Zellen]</translation>
        </message>
        <message>
            <source>The comparison grid is processed in tiles of this many cells a side (memory about 60 bytes per cell of a tile).</source>
            <extracomment>dem_compare.tile: help</extracomment>
            <translation>Das Vergleichsraster wird in Kacheln mit so vielen Zellen Seitenlänge verarbeitet (Speicher etwa 60 Byte je Zelle einer Kachel).</translation>
        </message>
        <message>
            <source>Dask scheduler for the tiles</source>
            <extracomment>dem_compare.scheduler: description; dsm_merge.scheduler: description; filter_linear_prediction.scheduler: description; filter_lowpass.scheduler: description; mosaic.scheduler: description</extracomment>
            <translation>Dask-Scheduler für die Kacheln</translation>
        </message>
        <message>
            <source>Empty: the tiles run one after the other in this process. 'local': a Dask cluster on this machine. tcp://host:8786: that Dask cluster, whose workers see the inputs and the output folder under the same paths. The result is the same; needs pip install "photodem[dask]".</source>
            <extracomment>dem_compare.scheduler: help; dsm_merge.scheduler: help; filter_linear_prediction.scheduler: help; filter_lowpass.scheduler: help; mosaic.scheduler: help</extracomment>
            <translation>Leer: Die Kacheln laufen nacheinander in diesem Prozess. 'local': ein Dask-Cluster auf diesem Rechner. tcp://host:8786: dieser Dask-Cluster, dessen Worker die Eingaben und den Ausgabeordner unter denselben Pfaden sehen. Das Ergebnis ist dasselbe; benötigt pip install "photodem[dask]".</translation>
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
            <source>Names of the class codes</source>
            <extracomment>dem_compare output class_names</extracomment>
            <translation>Namen der Klassencodes</translation>
        </message>
        <message>
            <source>Statistics per slope class</source>
            <extracomment>dem_compare output per_slope</extracomment>
            <translation>Statistik je Neigungsklasse</translation>
        </message>
        <message>
            <source>Statistics per object class</source>
            <extracomment>dem_compare output per_object</extracomment>
            <translation>Statistik je Objektklasse</translation>
        </message>
        <message>
            <source>Completeness per class</source>
            <extracomment>dem_compare output completeness</extracomment>
            <translation>Vollständigkeit je Klasse</translation>
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
            <source>Completeness as CSV</source>
            <extracomment>dem_compare output completeness_csv</extracomment>
            <translation>Vollständigkeit als CSV</translation>
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
            <extracomment>match_model: group; plugin/widgets/batch_dialog.py:148; plugin/widgets/batch_dialog.py:170; stereo_disparity: group</extracomment>
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
            <source>Matches the two images of a stereo model and grids the points to a DSM. fbm_lsm: image pyramids coarse to fine from the start points of edits.gpkg (or the height range), Förstner points, feature-based matching with robust consistency and a left–right check, least-squares matching at the finest level; failed windows are marked and matching goes on around them; groundel reduction (robust plane, σ1, σ2) and a finite-element surface that honours breaklines. dense: semi-global matching of every pixel of the epipolar pair, median per cell. Exclusion areas and boundaries of edits.gpkg are honoured (NaN). Writes dsm.tif, count.tif, report.json and report.html; fbm_lsm also sigma.tif and the raw and reduced points.</source>
            <extracomment>match_model: help</extracomment>
            <translation>Ordnet die beiden Bilder eines Stereomodells zu und rastert die Punkte zu einem DOM. fbm_lsm: Bildpyramiden von grob nach fein, ausgehend von den Startpunkten aus edits.gpkg (oder vom Höhenbereich), Förstner-Punkte, merkmalsbasierte Zuordnung mit robuster Konsistenzprüfung und Links-rechts-Prüfung, Kleinste-Quadrate-Zuordnung (LSM) auf der feinsten Stufe; fehlgeschlagene Fenster werden markiert und die Zuordnung wird um sie herum fortgesetzt; Reduktion je Geländeelement (robuste Ebene, σ1, σ2) und eine Finite-Elemente-Fläche, die Bruchkanten berücksichtigt. dense: Semi-Global Matching jedes Pixels des Epipolarbildpaars, Median je Zelle. Ausschlussflächen und Begrenzungen aus edits.gpkg werden beachtet (NaN). Schreibt dsm.tif, count.tif, report.json und report.html; fbm_lsm zusätzlich sigma.tif sowie die Roh- und die reduzierten Punkte.</translation>
        </message>
        <message>
            <source>fbm_lsm: hierarchical feature-based matching + LSM under the operator's control; dense: semi-global matching of every pixel.</source>
            <extracomment>match_model.method: help</extracomment>
            <translation>fbm_lsm: hierarchische merkmalsbasierte Zuordnung + LSM unter Kontrolle des Operateurs; dense: Semi-Global Matching jedes Pixels.</translation>
        </message>
        <message>
            <source>fbm_lsm</source>
            <extracomment>match_model.method: option</extracomment>
            <translation>fbm_lsm</translation>
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
            <extracomment>match_model.spacing: description; refine_object_space.spacing: description</extracomment>
            <translation>DOM-Gitterweite [m]</translation>
        </message>
        <message>
            <source>Default: 2 × the model's ground sample distance for fbm_lsm, 1 × for dense.</source>
            <extracomment>match_model.spacing: help</extracomment>
            <translation>Standard: 2 × Bodenpixelgröße des Modells für fbm_lsm, 1 × für dense.</translation>
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
            <source>Larger gaps stay empty (NaN). Default: 3 × the groundel size for fbm_lsm, 10 × spacing for dense.</source>
            <extracomment>match_model.max_gap: help</extracomment>
            <translation>Größere Lücken bleiben leer (NaN). Standard: 3 × Größe der Geländeelemente für fbm_lsm, 10 × Gitterweite für dense.</translation>
        </message>
        <message>
            <source>Strategy preset (fbm_lsm)</source>
            <extracomment>match_model.preset: description</extracomment>
            <translation>Strategievorgabe (fbm_lsm)</translation>
        </message>
        <message>
            <source>general (default): keeps buildings and trees (a DSM; roofs are searched up to 15 m above the ground), open terrain nearly as accurate as with terrain; urban: smaller windows and groundels for built-up areas; terrain (formerly flat): large windows and groundels, smooth surface without objects (nearly a DTM); hilly: medium; forest: lower envelope of the points per groundel. The options below override it.</source>
            <extracomment>match_model.preset: help</extracomment>
            <translation>allgemein (Standard): behält Gebäude und Bäume (ein DOM; Dächer werden bis 15 m über dem Boden gesucht), offenes Gelände fast so genau wie mit Gelände; städtisch: kleinere Fenster und Geländeelemente für bebaute Gebiete; Gelände (früher flach): große Fenster und Geländeelemente, glatte Fläche ohne Objekte (fast ein DGM); hügelig: mittlere; Wald: untere Einhüllende der Punkte je Geländeelement. Die unten angegebenen Optionen überschreiben die Vorgabe.</translation>
        </message>
        <message>
            <source>terrain</source>
            <extracomment>match_model.preset: option</extracomment>
            <translation>Gelände</translation>
        </message>
        <message>
            <source>hilly</source>
            <extracomment>filter_linear_prediction.preset: option; filter_lowpass.preset: option; match_model.preset: option</extracomment>
            <translation>hügelig</translation>
        </message>
        <message>
            <source>general</source>
            <extracomment>match_model.preset: option</extracomment>
            <translation>allgemein</translation>
        </message>
        <message>
            <source>urban</source>
            <extracomment>filter_linear_prediction.preset: option; filter_lowpass.preset: option; match_model.preset: option</extracomment>
            <translation>städtisch</translation>
        </message>
        <message>
            <source>forest</source>
            <extracomment>filter_linear_prediction.preset: option; filter_lowpass.preset: option; match_model.preset: option</extracomment>
            <translation>Wald</translation>
        </message>
        <message>
            <source>Matching window [px] (fbm_lsm)</source>
            <extracomment>match_model.fbm_window: description</extracomment>
            <translation>Zuordnungsfenster [px] (fbm_lsm)</translation>
        </message>
        <message>
            <source>Side of the window of the robust consistency. Default: the preset's (1.5 × on convergent drone and oblique pairs).</source>
            <extracomment>match_model.fbm_window: help</extracomment>
            <translation>Seitenlänge des Fensters der robusten Konsistenzprüfung. Standard: laut Vorgabe (1,5-fach bei konvergenten Drohnen- und Schrägbildpaaren).</translation>
        </message>
        <message>
            <source>Minimum correlation (fbm_lsm)</source>
            <extracomment>match_model.rho_min: description</extracomment>
            <translation>Mindestkorrelation (fbm_lsm)</translation>
        </message>
        <message>
            <source>Candidates with a smaller correlation coefficient are dropped. Default: 0.6.</source>
            <extracomment>match_model.rho_min: help</extracomment>
            <translation>Kandidaten mit kleinerem Korrelationskoeffizienten werden verworfen. Standard: 0,6.</translation>
        </message>
        <message>
            <source>Refine by least-squares matching (fbm_lsm)</source>
            <extracomment>match_model.lsm: description</extracomment>
            <translation>Durch Kleinste-Quadrate-Zuordnung verfeinern (fbm_lsm)</translation>
        </message>
        <message>
            <source>LSM at every point of the finest level; points whose LSM fails keep their feature-based value and a flag.</source>
            <extracomment>match_model.lsm: help</extracomment>
            <translation>LSM an jedem Punkt der feinsten Stufe; Punkte, bei denen die LSM fehlschlägt, behalten ihren merkmalsbasierten Wert und werden markiert.</translation>
        </message>
        <message>
            <source>Groundel size [m] (fbm_lsm)</source>
            <extracomment>match_model.groundel: description</extracomment>
            <translation>Größe der Geländeelemente [m] (fbm_lsm)</translation>
        </message>
        <message>
            <source>Side of the cells of the robust reduction. Default: the preset's multiple of the GSD (general: 20, urban: 10, terrain: 40 × GSD).</source>
            <extracomment>match_model.groundel: help</extracomment>
            <translation>Seitenlänge der Zellen der robusten Reduktion. Standard: das Vielfache der GSD laut Vorgabe (allgemein: 20, städtisch: 10, Gelände: 40 × GSD).</translation>
        </message>
        <message>
            <source>Groundel reduction (fbm_lsm)</source>
            <extracomment>match_model.reduction: description</extracomment>
            <translation>Reduktion je Geländeelement (fbm_lsm)</translation>
        </message>
        <message>
            <source>l1: robust tilted plane; median; lower: lower envelope (vegetation). Default: the preset's.</source>
            <extracomment>match_model.reduction: help</extracomment>
            <translation>l1: robuste geneigte Ebene; Median; untere Hülle: untere Einhüllende (Vegetation). Standard: laut Vorgabe.</translation>
        </message>
        <message>
            <source>l1</source>
            <extracomment>match_model.reduction: option</extracomment>
            <translation>l1</translation>
        </message>
        <message>
            <source>median</source>
            <extracomment>dsm_merge.mode: option; match_model.reduction: option</extracomment>
            <translation>Median</translation>
        </message>
        <message>
            <source>lower</source>
            <extracomment>match_model.reduction: option</extracomment>
            <translation>untere Hülle</translation>
        </message>
        <message>
            <source>Point format (fbm_lsm)</source>
            <extracomment>match_model.points_format: description</extracomment>
            <translation>Punktformat (fbm_lsm)</translation>
        </message>
        <message>
            <source>GeoPackage, or LAS (needs the Python package laspy).</source>
            <extracomment>match_model.points_format: help</extracomment>
            <translation>GeoPackage oder LAS (erfordert das Python-Paket laspy).</translation>
        </message>
        <message>
            <source>gpkg</source>
            <extracomment>match_model.points_format: option</extracomment>
            <translation>gpkg</translation>
        </message>
        <message>
            <source>las</source>
            <extracomment>match_model.points_format: option</extracomment>
            <translation>las</translation>
        </message>
        <message>
            <source>Use start points (fbm_lsm)</source>
            <extracomment>match_model.use_start_points: description</extracomment>
            <translation>Startpunkte verwenden (fbm_lsm)</translation>
        </message>
        <message>
            <source>Start from the start points of edits.gpkg; without any, the whole height range is searched at the coarsest level.</source>
            <extracomment>match_model.use_start_points: help</extracomment>
            <translation>Von den Startpunkten aus edits.gpkg ausgehen; ohne Startpunkte wird auf der gröbsten Stufe der gesamte Höhenbereich durchsucht.</translation>
        </message>
        <message>
            <source>Match foreshortened slopes (dense, convergent or wide base)</source>
            <extracomment>match_model.slant_passes: description</extracomment>
            <translation>Verkürzte Hänge zuordnen (dense, konvergent oder große Basis)</translation>
        </message>
        <message>
            <source>Convergent models and models with a base of at least half the flying height: also match against the right image stretched by 0.7 and 1.4, for slopes and roof faces one camera sees foreshortened, refined by least-squares matching. More cells measured as precisely as the others, about 5–6 × the time.</source>
            <extracomment>match_model.slant_passes: help</extracomment>
            <translation>Konvergente Modelle und Modelle mit einer Basis von mindestens der halben Flughöhe: zusätzlich gegen das um 0,7 und 1,4 gestreckte rechte Bild zuordnen, für Hänge und Dachflächen, die eine Kamera verkürzt sieht, verfeinert durch Kleinste-Quadrate-Zuordnung. Mehr Zellen gemessen, so genau wie die übrigen, etwa 5–6 × die Rechenzeit.</translation>
        </message>
        <message>
            <source>Match once more along the first DSM (dense, convergent)</source>
            <extracomment>match_model.guided_pass: description</extracomment>
            <translation>Noch einmal entlang des ersten DOM zuordnen (dense, konvergent)</translation>
        </message>
        <message>
            <source>Convergent models: match again within ± 8 px of the first DSM's disparities, against the right image warped by them, and keep the new heights where least-squares matching and a uniqueness test along the row confirm them. Measures slopes across the base (embankments, ditch sides) that the first pass flattens; about 1.3–1.4 × the time.</source>
            <extracomment>match_model.guided_pass: help</extracomment>
            <translation>Konvergente Modelle: noch einmal innerhalb von ± 8 px der Disparitäten des ersten DOM zuordnen, gegen das mit ihnen entzerrte rechte Bild, und die neuen Höhen dort behalten, wo Kleinste-Quadrate-Zuordnung und ein Eindeutigkeitstest entlang der Zeile sie bestätigen. Misst Hänge quer zur Basis (Dämme, Grabenböschungen), die der erste Durchgang einebnet; etwa 1,3–1,4 × die Rechenzeit.</translation>
        </message>
        <message>
            <source>DSM</source>
            <extracomment>match_model output dsm; mosaic.dsm: description; plugin/app/map_window.py:456; plugin/qgis/workspace.py:426</extracomment>
            <translation>DOM</translation>
        </message>
        <message>
            <source>Points per cell</source>
            <extracomment>interpolate_dem output count; match_model output count</extracomment>
            <translation>Punkte je Zelle</translation>
        </message>
        <message>
            <source>σ of the heights [m]</source>
            <extracomment>match_model output sigma; refine_object_space output sigma</extracomment>
            <translation>σ der Höhen [m]</translation>
        </message>
        <message>
            <source>Points</source>
            <extracomment>match_model output points</extracomment>
            <translation>Punkte</translation>
        </message>
        <message>
            <source>Reduced points</source>
            <extracomment>match_model output reduced</extracomment>
            <translation>Reduzierte Punkte</translation>
        </message>
        <message>
            <source>Report (JSON)</source>
            <extracomment>filter_evaluate output report; filter_linear_prediction output report; filter_lowpass output report; match_model output report; refine_object_space output report</extracomment>
            <translation>Bericht (JSON)</translation>
        </message>
        <message>
            <source>Report (HTML)</source>
            <extracomment>match_model output report_html</extracomment>
            <translation>Bericht (HTML)</translation>
        </message>
        <message>
            <source>Metrics</source>
            <extracomment>match_model output metrics; refine_object_space output metrics</extracomment>
            <translation>Kennzahlen</translation>
        </message>
        <message>
            <source>Merge DSMs</source>
            <extracomment>dsm_merge: name; plugin/widgets/batch_dialog.py:171</extracomment>
            <translation>DOMs zusammenführen</translation>
        </message>
        <message>
            <source>Surfaces</source>
            <extracomment>dsm_merge: group; interpolate_dem: group; plugin/widgets/qc_panel.py:121; refine_object_space: group</extracomment>
            <translation>Oberflächen</translation>
        </message>
        <message>
            <source>Merges model DSMs into one DSM on a common grid: the union of their extents at the finest input cell size (or at the given spacing), in the CRS of the first input; inputs with another grid or CRS are resampled bilinearly, window by window. Modes: median or mean of the heights per cell; best_sigma takes the height of the input with the smallest σ, where σ is a second band of the input or a raster &lt;name&gt;_sigma.tif or sigma.tif beside it — inputs without σ are used only where no input with σ has a height (as their median), so without any σ best_sigma is the median. Writes the DSM, &lt;name&gt;_count.tif (inputs per cell) and the seam statistics of every overlapping pair (Δh = a − b: count, mean, median, std, RMS, NMAD) as &lt;name&gt;_seams.json and .csv. Walls are kept: where the inputs of a cell differ by more than the step threshold (one has the roof, another the ground), the largest consistent group of heights is used instead of averaging them, and resampled inputs take the nearest cell at steps.</source>
            <extracomment>dsm_merge: help</extracomment>
            <translation>Führt Modell-DOMs auf einem gemeinsamen Raster zu einem DOM zusammen: die Vereinigung ihrer Ausdehnungen mit der feinsten Zellgröße der Eingaben (oder der angegebenen Zellgröße), im KBS der ersten Eingabe; Eingaben mit anderem Raster oder KBS werden fensterweise bilinear umgetastet. Modi: Median oder Mittel der Höhen je Zelle; best_sigma nimmt die Höhe der Eingabe mit dem kleinsten σ, wobei σ ein zweiter Kanal der Eingabe oder ein Raster &lt;Name&gt;_sigma.tif oder sigma.tif daneben ist — Eingaben ohne σ werden nur dort verwendet, wo keine Eingabe mit σ eine Höhe hat (als ihr Median), ohne jedes σ ist best_sigma also der Median. Schreibt das DOM, &lt;Name&gt;_count.tif (Eingaben je Zelle) und die Nahtstatistik jedes überlappenden Paars (Δh = a − b: Anzahl, Mittel, Median, Standardabweichung, RMS, NMAD) als &lt;Name&gt;_seams.json und .csv. Wände bleiben erhalten: wo die Eingaben einer Zelle um mehr als die Stufenschwelle voneinander abweichen (eine hat das Dach, eine andere den Boden), wird die größte in sich stimmige Gruppe von Höhen verwendet statt sie zu mitteln, und umgetastete Eingaben nehmen an Stufen die nächste Zelle.</translation>
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
            <source>Step threshold [m]</source>
            <extracomment>dsm_merge.step: description</extracomment>
            <translation>Stufenschwelle [m]</translation>
        </message>
        <message>
            <source>Inputs of a cell that differ by more than this see different surfaces (a wall): they are not averaged. 0 = plain median / mean.</source>
            <extracomment>dsm_merge.step: help</extracomment>
            <translation>Eingaben einer Zelle, die um mehr als diesen Wert voneinander abweichen, sehen verschiedene Oberflächen (eine Wand): sie werden nicht gemittelt. 0 = einfacher Median / Mittelwert.</translation>
        </message>
        <message>
            <source>The merged DSM is processed in tiles of this many cells a side (memory about 8 bytes per cell and input of a tile).</source>
            <extracomment>dsm_merge.tile: help</extracomment>
            <translation>Das zusammengeführte DOM wird in Kacheln mit so vielen Zellen Seitenlänge verarbeitet (Speicher etwa 8 Byte je Zelle und Eingabe einer Kachel).</translation>
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
            <extracomment>algorithms/input_errors.py:81; interpolate_dem output dem; interpolate_dem.output: description; plugin/qgis/qc_dock.py:192; plugin/widgets/qc_panel.py:130</extracomment>
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
            <extracomment>filter_linear_prediction.project: description; filter_lowpass.project: description; interpolate_dem.project: description</extracomment>
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
            <source>Interpolation method</source>
            <extracomment>interpolate_dem.method: description</extracomment>
            <translation>Interpolationsverfahren</translation>
        </message>
        <message>
            <source>membrane: median per cell, empty cells by membrane interpolation; fe: finite elements fitted to all points with curvature regularisation (smooth between sparse points, breaklines allow kinks).</source>
            <extracomment>interpolate_dem.method: help</extracomment>
            <translation>membrane: Median je Zelle, leere Zellen durch Membran-Interpolation; fe: an alle Punkte angepasste finite Elemente mit Krümmungsregularisierung (glatt zwischen spärlichen Punkten, Bruchkanten erlauben Knicke).</translation>
        </message>
        <message>
            <source>membrane</source>
            <extracomment>interpolate_dem.method: option</extracomment>
            <translation>membrane</translation>
        </message>
        <message>
            <source>fe</source>
            <extracomment>interpolate_dem.method: option</extracomment>
            <translation>fe</translation>
        </message>
        <message>
            <source>Smoothing (fe)</source>
            <extracomment>interpolate_dem.smoothing: description</extracomment>
            <translation>Glättung (fe)</translation>
        </message>
        <message>
            <source>Weight of the curvature equations relative to a point (fe only): 0.01–0.1 interpolates, 1–10 smooths noisy points.</source>
            <extracomment>interpolate_dem.smoothing: help</extracomment>
            <translation>Gewicht der Krümmungsgleichungen relativ zu einem Punkt (nur fe): 0,01–0,1 interpoliert, 1–10 glättet verrauschte Punkte.</translation>
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
            <source>Refine DSM in object space (multi-image LSM)</source>
            <extracomment>refine_object_space: name</extracomment>
            <translation>DOM im Objektraum verfeinern (Mehrbild-LSM)</translation>
        </message>
        <message>
            <source>Refines a DSM with all images that see it (2 … N) by least-squares matching in object space: per DSM tile, heights on geometry nodes (every facet_px image pixels), object grey values on a finer grid and a gain and offset per image are adjusted together (Gauss–Newton, conjugate gradients) so that every image shows the same grey values at the projection of the surface, with curvature regularisation, coarse to fine over image-pyramid levels. The input DSM must be within a few pixels of parallax. Writes dsm.tif (refined heights, float32, NaN where not refined), sigma.tif (σ of the height per cell from the normal equations, m) and report.json (images and iterations per tile, σ0 in grey values, mean/median σ, failures). Exclusion areas and cells outside the boundaries of edits.gpkg are NaN.</source>
            <extracomment>refine_object_space: help</extracomment>
            <translation>Verfeinert ein DOM mit allen Bildern, die es sehen (2 … N), durch Kleinste-Quadrate-Zuordnung im Objektraum: je DOM-Kachel werden Höhen auf Geometrieknoten (alle facet_px Bildpixel), Objektgrauwerte auf einem feineren Raster sowie Verstärkung und Offset je Bild gemeinsam ausgeglichen (Gauß–Newton, konjugierte Gradienten), sodass jedes Bild an der Projektion der Oberfläche dieselben Grauwerte zeigt, mit Krümmungsregularisierung, grob nach fein über die Stufen der Bildpyramide. Das Eingangs-DOM muss bis auf wenige Pixel Parallaxe stimmen. Schreibt dsm.tif (verfeinerte Höhen, float32, NaN wo nicht verfeinert), sigma.tif (σ der Höhe je Zelle aus den Normalgleichungen, m) und report.json (Bilder und Iterationen je Kachel, σ0 in Grauwerten, mittleres/medianes σ, Fehlschläge). Ausschlussflächen und Zellen außerhalb der Begrenzungen von edits.gpkg sind NaN.</translation>
        </message>
        <message>
            <source>DSM to refine</source>
            <extracomment>refine_object_space.dsm: description</extracomment>
            <translation>Zu verfeinerndes DOM</translation>
        </message>
        <message>
            <source>Float GeoTIFF in the project CRS (e.g. dsm.tif of 'Match stereo model').</source>
            <extracomment>refine_object_space.dsm: help</extracomment>
            <translation>Gleitkomma-GeoTIFF im Projekt-KBS (z. B. dsm.tif von „Stereomodell zuordnen“).</translation>
        </message>
        <message>
            <source>Default: &lt;project&gt;/products/dsm_refined/&lt;DSM name&gt;/.</source>
            <extracomment>refine_object_space.output: help</extracomment>
            <translation>Standard: &lt;Projekt&gt;/products/dsm_refined/&lt;DOM-Name&gt;/.</translation>
        </message>
        <message>
            <source>Cell size of the refined DSM. Default: the input DSM's.</source>
            <extracomment>refine_object_space.spacing: help</extracomment>
            <translation>Zellengröße des verfeinerten DOM. Standard: die des Eingangs-DOM.</translation>
        </message>
        <message>
            <source>Pyramid levels</source>
            <extracomment>refine_object_space.levels: description</extracomment>
            <translation>Pyramidenstufen</translation>
        </message>
        <message>
            <source>Image-pyramid levels, coarse to fine; each level doubles the pull-in range (≈ 2 px of parallax on the top level).</source>
            <extracomment>refine_object_space.levels: help</extracomment>
            <translation>Stufen der Bildpyramide, grob nach fein; jede Stufe verdoppelt den Konvergenzbereich (≈ 2 px Parallaxe auf der obersten Stufe).</translation>
        </message>
        <message>
            <source>Iterations per level</source>
            <extracomment>refine_object_space.max_iter: description</extracomment>
            <translation>Iterationen je Stufe</translation>
        </message>
        <message>
            <source>Gauss–Newton iterations per level at most.</source>
            <extracomment>refine_object_space.max_iter: help</extracomment>
            <translation>Höchstens so viele Gauß–Newton-Iterationen je Stufe.</translation>
        </message>
        <message>
            <source>Regularisation share</source>
            <extracomment>refine_object_space.regularisation: description</extracomment>
            <translation>Anteil der Regularisierung</translation>
        </message>
        <message>
            <source>Weight of the curvature regularisation relative to the image data on the height diagonal of the normal equations (0 = none).</source>
            <extracomment>refine_object_space.regularisation: help</extracomment>
            <translation>Gewicht der Krümmungsregularisierung relativ zu den Bilddaten auf der Höhendiagonale der Normalgleichungen (0 = keine).</translation>
        </message>
        <message>
            <source>Regularisation</source>
            <extracomment>refine_object_space.regularisation_mode: description</extracomment>
            <translation>Regularisierung</translation>
        </message>
        <message>
            <source>curvature: smooth surface (thesis); correction: smooth only the change to the input DSM (keeps buildings and edges).</source>
            <extracomment>refine_object_space.regularisation_mode: help</extracomment>
            <translation>curvature: glatte Oberfläche (wie in der Dissertation); correction: nur die Änderung am Eingangs-DOM glätten (erhält Gebäude und Kanten).</translation>
        </message>
        <message>
            <source>curvature</source>
            <extracomment>refine_object_space.regularisation_mode: option</extracomment>
            <translation>Krümmung</translation>
        </message>
        <message>
            <source>correction</source>
            <extracomment>refine_object_space.regularisation_mode: option</extracomment>
            <translation>Korrektur</translation>
        </message>
        <message>
            <source>Geometry facet [px]</source>
            <extracomment>refine_object_space.facet_px: description</extracomment>
            <translation>Geometriefacette [px]</translation>
        </message>
        <message>
            <source>Spacing of the height unknowns in image pixels (thesis: 8).</source>
            <extracomment>refine_object_space.facet_px: help</extracomment>
            <translation>Abstand der Höhenunbekannten in Bildpixeln (Dissertation: 8).</translation>
        </message>
        <message>
            <source>Grey-value facet [px]</source>
            <extracomment>refine_object_space.grey_px: description</extracomment>
            <translation>Grauwertfacette [px]</translation>
        </message>
        <message>
            <source>Spacing of the object grey values in image pixels (thesis: 2).</source>
            <extracomment>refine_object_space.grey_px: help</extracomment>
            <translation>Abstand der Objektgrauwerte in Bildpixeln (Dissertation: 2).</translation>
        </message>
        <message>
            <source>Comma-separated image names. Default: every image whose footprint covers a tile.</source>
            <extracomment>refine_object_space.images: help</extracomment>
            <translation>Bildnamen, durch Kommas getrennt. Standard: jedes Bild, dessen Fußabdruck eine Kachel überdeckt.</translation>
        </message>
        <message>
            <source>Side of the computation windows (plus overlap); bounds the memory.</source>
            <extracomment>refine_object_space.tile: help</extracomment>
            <translation>Seitenlänge der Rechenfenster (zuzüglich Überlappung); begrenzt den Speicherbedarf.</translation>
        </message>
        <message>
            <source>Refined DSM</source>
            <extracomment>refine_object_space output dsm</extracomment>
            <translation>Verfeinertes DOM</translation>
        </message>
        <message>
            <source>Filter DSM to DTM (iterative low-pass)</source>
            <extracomment>filter_lowpass: name</extracomment>
            <translation>DOM zu DGM filtern (iterativer Tiefpass)</translation>
        </message>
        <message>
            <source>DTM filtering</source>
            <extracomment>filter_evaluate: group; filter_linear_prediction: group; filter_lowpass: group</extracomment>
            <translation>DGM-Filterung</translation>
        </message>
        <message>
            <source>Iterative robust low-pass filtering (the 'Phoenics' method): the surface is smoothed with a window that shrinks from iteration to iteration (a least-squares plane through the remaining cells of the window), the difference model DSM − smoothed surface is formed, cells higher than the iteration's threshold (buildings, vegetation) or far below it (blunders) are eliminated, and the holes are filled from the surrounding ground by membrane interpolation. Exclusion areas with action 'keep' keep the DSM as DTM (embankments, dams); 'remove' areas are eliminated before the first iteration and bridged (forests); manual ground points are hard constraints (the DTM passes through them); smoothing and hole filling do not cross breaklines. The largest window should be 2–3 × the largest building width. Writes dtm.tif, ndsm.tif, mask.tif or labels.txt, report.json/html and, optionally, the difference model of every iteration.</source>
            <extracomment>filter_lowpass: help</extracomment>
            <translation>Iterative robuste Tiefpassfilterung (das „Phoenics“-Verfahren): Die Oberfläche wird mit einem Fenster geglättet, das von Iteration zu Iteration kleiner wird (eine ausgleichende Ebene durch die verbliebenen Zellen des Fensters), das Differenzmodell DOM − geglättete Oberfläche wird gebildet, Zellen, die höher als die Schwelle der Iteration liegen (Gebäude, Vegetation) oder weit darunter (Fehlmessungen), werden eliminiert, und die Löcher werden aus dem umgebenden Gelände durch Membraninterpolation gefüllt. Ausschlussflächen mit der Aktion 'keep' behalten das DOM als DGM (Dämme, Bahndämme); 'remove'-Flächen werden vor der ersten Iteration eliminiert und überbrückt (Wälder); manuelle Bodenpunkte sind feste Bedingungen (das DGM geht durch sie hindurch); Glättung und Lochfüllung greifen nicht über Bruchkanten. Das größte Fenster sollte 2–3 × so breit wie das breiteste Gebäude sein. Schreibt dtm.tif, ndsm.tif, mask.tif oder labels.txt, report.json/html und auf Wunsch das Differenzmodell jeder Iteration.</translation>
        </message>
        <message>
            <source>DSM raster or points</source>
            <extracomment>filter_linear_prediction.input: description; filter_lowpass.input: description</extracomment>
            <translation>DOM-Raster oder Punkte</translation>
        </message>
        <message>
            <source>A DSM GeoTIFF (nodata = no height), or points: XYZ text with whitespace, comma, semicolon or tab separators (extra columns ignored), GeoPackage points from matching (with sigma_z), LAS/LAZ when laspy is installed.</source>
            <extracomment>filter_linear_prediction.input: help; filter_lowpass.input: help</extracomment>
            <translation>Ein DOM als GeoTIFF (NoData = keine Höhe) oder Punkte: XYZ-Text mit Leerzeichen, Komma, Semikolon oder Tabulator als Trennzeichen (weitere Spalten werden ignoriert), GeoPackage-Punkte aus der Zuordnung (mit sigma_z), LAS/LAZ, wenn laspy installiert ist.</translation>
        </message>
        <message>
            <source>Receives dtm.tif, ndsm.tif, mask.tif (raster input) or labels.txt (point input), report.json and report.html. Written completely or not at all.</source>
            <extracomment>filter_linear_prediction.output: help; filter_lowpass.output: help</extracomment>
            <translation>Erhält dtm.tif, ndsm.tif, mask.tif (Rastereingabe) oder labels.txt (Punkteingabe), report.json und report.html. Wird vollständig oder gar nicht geschrieben.</translation>
        </message>
        <message>
            <source>Parameter preset</source>
            <extracomment>filter_linear_prediction.preset: description; filter_lowpass.preset: description</extracomment>
            <translation>Parametervorgabe</translation>
        </message>
        <message>
            <source>auto (the default) measures the input's terrain slope and vegetated share and takes steep for steep vegetated ground, else default, and reports why; default serves most terrain types; flat, hilly, urban, forest and steep are tuned variants. Options given below override the preset.</source>
            <extracomment>filter_linear_prediction.preset: help; filter_lowpass.preset: help</extracomment>
            <translation>auto (die Vorgabe) misst die Geländeneigung und den bewachsenen Anteil der Eingabe und wählt steep für steiles bewachsenes Gelände, sonst default, und berichtet, warum; default dient den meisten Geländetypen; flat, hilly, urban, forest und steep sind abgestimmte Varianten. Die unten angegebenen Optionen überschreiben die Vorgabe.</translation>
        </message>
        <message>
            <source>default</source>
            <extracomment>filter_linear_prediction.preset: option; filter_lowpass.preset: option</extracomment>
            <translation>Standard</translation>
        </message>
        <message>
            <source>flat</source>
            <extracomment>filter_linear_prediction.preset: option; filter_lowpass.preset: option</extracomment>
            <translation>flach</translation>
        </message>
        <message>
            <source>auto</source>
            <extracomment>filter_linear_prediction.preset: option; filter_lowpass.preset: option; georeference_polygons.objects: option; georeference_polygons.search: option</extracomment>
            <translation>automatisch</translation>
        </message>
        <message>
            <source>Its exclusion areas (keep/remove), manual ground points and breaklines are honoured.</source>
            <extracomment>filter_linear_prediction.project: help; filter_lowpass.project: help</extracomment>
            <translation>Seine Ausschlussflächen (keep/remove), manuellen Bodenpunkte und Bruchkanten werden berücksichtigt.</translation>
        </message>
        <message>
            <source>Grid spacing for point input [m]</source>
            <extracomment>filter_linear_prediction.spacing: description; filter_lowpass.spacing: description</extracomment>
            <translation>Rasterweite für Punkteingabe [m]</translation>
        </message>
        <message>
            <source>Default: about the mean point spacing. Ignored for raster input.</source>
            <extracomment>filter_linear_prediction.spacing: help; filter_lowpass.spacing: help</extracomment>
            <translation>Standard: etwa der mittlere Punktabstand. Wird bei Rastereingabe ignoriert.</translation>
        </message>
        <message>
            <source>CRS of point input</source>
            <extracomment>filter_linear_prediction.crs: description; filter_lowpass.crs: description</extracomment>
            <translation>KBS der Punkteingabe</translation>
        </message>
        <message>
            <source>CRS of text points. Default: the project's, else the input's own.</source>
            <extracomment>filter_linear_prediction.crs: help; filter_lowpass.crs: help</extracomment>
            <translation>KBS von Textpunkten. Standard: das des Projekts, sonst das der Eingabe.</translation>
        </message>
        <message>
            <source>Largest smoothing window [m]</source>
            <extracomment>filter_lowpass.max_window: description</extracomment>
            <translation>Größtes Glättungsfenster [m]</translation>
        </message>
        <message>
            <source>Window of the first iteration; 2–3 × the largest building width. The windows of later iterations shrink in the preset's proportions.</source>
            <extracomment>filter_lowpass.max_window: help</extracomment>
            <translation>Fenster der ersten Iteration; 2–3 × die Breite des breitesten Gebäudes. Die Fenster späterer Iterationen schrumpfen in den Verhältnissen der Vorgabe.</translation>
        </message>
        <message>
            <source>Iterations</source>
            <extracomment>filter_lowpass.iterations: description; plugin/widgets/georef_review.py:55</extracomment>
            <translation>Iterationen</translation>
        </message>
        <message>
            <source>Number of smoothing/elimination iterations.</source>
            <extracomment>filter_lowpass.iterations: help</extracomment>
            <translation>Anzahl der Glättungs-/Eliminationsiterationen.</translation>
        </message>
        <message>
            <source>Final height threshold [m]</source>
            <extracomment>filter_lowpass.threshold: description</extracomment>
            <translation>Letzte Höhenschwelle [m]</translation>
        </message>
        <message>
            <source>Cells higher than this above the smoothed surface are objects in the last iteration; earlier iterations use the preset's larger thresholds.</source>
            <extracomment>filter_lowpass.threshold: help</extracomment>
            <translation>Zellen, die mehr als dies über der geglätteten Oberfläche liegen, sind in der letzten Iteration Objekte; frühere Iterationen verwenden die größeren Schwellen der Vorgabe.</translation>
        </message>
        <message>
            <source>Terrain slope allowance [%]</source>
            <extracomment>filter_linear_prediction.slope: description; filter_lowpass.slope: description</extracomment>
            <translation>Zuschlag für Geländeneigung [%]</translation>
        </message>
        <message>
            <source>Allowance for breaks of slope (ridges, hill tops): every threshold grows by slope/100 × window/4.</source>
            <extracomment>filter_lowpass.slope: help</extracomment>
            <translation>Zuschlag für Neigungswechsel (Kämme, Kuppen): jede Schwelle wächst um Neigung/100 × Fenster/4.</translation>
        </message>
        <message>
            <source>Write difference model of every iteration</source>
            <extracomment>filter_lowpass.write_iterations: description</extracomment>
            <translation>Differenzmodell jeder Iteration schreiben</translation>
        </message>
        <message>
            <source>Writes diff_01.tif, diff_02.tif … (DSM − smoothed surface) for inspection.</source>
            <extracomment>filter_lowpass.write_iterations: help</extracomment>
            <translation>Schreibt diff_01.tif, diff_02.tif … (DOM − geglättete Oberfläche) zur Kontrolle.</translation>
        </message>
        <message>
            <source>Larger DSMs are filtered in overlapping tiles of at most this many cells a side (overlap included; the filter's reach). Default 4096; memory about 150 bytes per cell of a tile.</source>
            <extracomment>filter_linear_prediction.tile: help; filter_lowpass.tile: help</extracomment>
            <translation>Größere DOMs werden in überlappenden Kacheln von höchstens so vielen Zellen Seitenlänge gefiltert (einschließlich der Überlappung, der Reichweite des Filters). Standard 4096; Speicher etwa 150 Byte je Zelle einer Kachel.</translation>
        </message>
        <message>
            <source>DTM</source>
            <extracomment>filter_linear_prediction output dtm; filter_lowpass output dtm; mosaic.dtm: description; plugin/app/map_window.py:456; plugin/qgis/workspace.py:426; plugin/widgets/qc_filter.py:50</extracomment>
            <translation>DGM</translation>
        </message>
        <message>
            <source>Normalised DSM (DSM − DTM)</source>
            <extracomment>filter_linear_prediction output ndsm; filter_lowpass output ndsm</extracomment>
            <translation>Normalisiertes DOM (DOM − DGM)</translation>
        </message>
        <message>
            <source>Object mask (raster input)</source>
            <extracomment>filter_linear_prediction output mask; filter_lowpass output mask</extracomment>
            <translation>Objektmaske (Rastereingabe)</translation>
        </message>
        <message>
            <source>Labels per input point (point input)</source>
            <extracomment>filter_linear_prediction output labels; filter_lowpass output labels</extracomment>
            <translation>Klassen je Eingabepunkt (Punkteingabe)</translation>
        </message>
        <message>
            <source>Eliminated share, parameters, ground-point check</source>
            <extracomment>filter_lowpass output metrics</extracomment>
            <translation>Eliminierter Anteil, Parameter, Bodenpunktprüfung</translation>
        </message>
        <message>
            <source>Evaluate ground filtering (Type I/II, kappa, DTM accuracy)</source>
            <extracomment>filter_evaluate: name</extracomment>
            <translation>Bodenfilterung bewerten (Typ I/II, Kappa, DGM-Genauigkeit)</translation>
        </message>
        <message>
            <source>Compares a filter's ground/object labels with reference labels using the ISPRS filter test measures (Sithole &amp; Vosselman 2004): Type I = ground rejected / all ground, Type II = objects accepted as ground / all objects, total error and Cohen's kappa, in percent. Labels: the filter's labels.txt (one 0/1 per input point) or mask.tif; reference: a text file whose last column (or the given column) is the label, e.g. the ISPRS samples 'X Y Z label' (0 = ground, 1 = object), or a reference mask raster. With a DTM, its differences to a reference DTM (mean, std, RMS, NMAD, 95 % |Δh|) and, for a reference with coordinates, at the reference ground points are reported. Writes report.json and report.csv.</source>
            <extracomment>filter_evaluate: help</extracomment>
            <translation>Vergleicht die Boden-/Objekt-Klassifikation eines Filters mit Referenzklassen nach den Maßen des ISPRS-Filtertests (Sithole &amp; Vosselman 2004): Typ I = verworfener Boden / gesamter Boden, Typ II = als Boden angenommene Objekte / alle Objekte, Gesamtfehler und Cohens Kappa, in Prozent. Klassen: labels.txt des Filters (eine 0/1 je Eingabepunkt) oder mask.tif; Referenz: eine Textdatei, deren letzte (oder die angegebene) Spalte die Klasse ist, z. B. die ISPRS-Proben „X Y Z Klasse“ (0 = Boden, 1 = Objekt), oder ein Referenz-Maskenraster. Mit einem DGM werden seine Differenzen zu einem Referenz-DGM (Mittel, Standardabweichung, RMS, NMAD, 95 % |Δh|) und, bei einer Referenz mit Koordinaten, an den Referenz-Bodenpunkten ausgegeben. Schreibt report.json und report.csv.</translation>
        </message>
        <message>
            <source>Filter labels (labels.txt or mask raster)</source>
            <extracomment>filter_evaluate.labels: description</extracomment>
            <translation>Klassen des Filters (labels.txt oder Maskenraster)</translation>
        </message>
        <message>
            <source>0 = ground, 1 = object; a text file lists the same points in the same order as the reference.</source>
            <extracomment>filter_evaluate.labels: help</extracomment>
            <translation>0 = Boden, 1 = Objekt; eine Textdatei führt dieselben Punkte in derselben Reihenfolge wie die Referenz.</translation>
        </message>
        <message>
            <source>Reference labels (text or mask raster)</source>
            <extracomment>filter_evaluate.reference: description</extracomment>
            <translation>Referenzklassen (Text oder Maskenraster)</translation>
        </message>
        <message>
            <source>Text with the label in the last column (or the column below), e.g. 'X Y Z label'; or a mask raster (1 = object, 0 = ground).</source>
            <extracomment>filter_evaluate.reference: help</extracomment>
            <translation>Text mit der Klasse in der letzten Spalte (oder der unten angegebenen), z. B. „X Y Z Klasse“; oder ein Maskenraster (1 = Objekt, 0 = Boden).</translation>
        </message>
        <message>
            <source>Label column of the reference text</source>
            <extracomment>filter_evaluate.column: description</extracomment>
            <translation>Klassenspalte des Referenztextes</translation>
        </message>
        <message>
            <source>1 = first column. Default: a column named label/class, else the last.</source>
            <extracomment>filter_evaluate.column: help</extracomment>
            <translation>1 = erste Spalte. Standard: eine Spalte namens label/class, sonst die letzte.</translation>
        </message>
        <message>
            <source>Filtered DTM</source>
            <extracomment>filter_evaluate.dtm: description</extracomment>
            <translation>Gefiltertes DGM</translation>
        </message>
        <message>
            <source>The filter's dtm.tif, checked against the reference DTM and/or the reference ground points.</source>
            <extracomment>filter_evaluate.dtm: help</extracomment>
            <translation>dtm.tif des Filters, geprüft gegen das Referenz-DGM und/oder die Referenz-Bodenpunkte.</translation>
        </message>
        <message>
            <source>Reference DTM</source>
            <extracomment>filter_evaluate.reference_dtm: description</extracomment>
            <translation>Referenz-DGM</translation>
        </message>
        <message>
            <source>Δh = DTM − reference DTM on the reference grid.</source>
            <extracomment>filter_evaluate.reference_dtm: help</extracomment>
            <translation>Δh = DGM − Referenz-DGM im Raster der Referenz.</translation>
        </message>
        <message>
            <source>Receives report.json and report.csv (written completely or not at all).</source>
            <extracomment>filter_evaluate.output: help</extracomment>
            <translation>Erhält report.json und report.csv (vollständig oder gar nicht geschrieben).</translation>
        </message>
        <message>
            <source>Report (CSV, one row)</source>
            <extracomment>filter_evaluate output csv</extracomment>
            <translation>Bericht (CSV, eine Zeile)</translation>
        </message>
        <message>
            <source>Type I/II, total error, kappa [%], DTM statistics</source>
            <extracomment>filter_evaluate output metrics</extracomment>
            <translation>Typ I/II, Gesamtfehler, Kappa [%], DGM-Statistik</translation>
        </message>
        <message>
            <source>Filter DSM to DTM (robust linear prediction)</source>
            <extracomment>filter_linear_prediction: name</extracomment>
            <translation>DOM zu DGM filtern (robuste lineare Prädiktion)</translation>
        </message>
        <message>
            <source>Hierarchical robust linear prediction (Kraus &amp; Pfeifer): on a pyramid of the DSM (lowest cell of every 2×2 block, up to the preset's coarse cell size) the terrain is predicted level by level, coarse to fine. At every level a trend (a robust plane, then the coarser level's DTM) is removed, a Gaussian covariance (signal variance, noise share, correlation length) is estimated from the data, and the heights are predicted with filtering; robust iterations give cells below the surface full weight and cells above it less (zero beyond the cut-off), so the surface sinks onto the ground and buildings and woods are bridged. Exclusion areas 'keep' keep the DSM as DTM, 'remove' areas are bridged, manual ground points are hard constraints and breaklines stop the prediction from reaching across. Writes dtm.tif, ndsm.tif, mask.tif or labels.txt, report.json/html and, optionally, the DTM of every level.</source>
            <extracomment>filter_linear_prediction: help</extracomment>
            <translation>Hierarchische robuste lineare Prädiktion (Kraus &amp; Pfeifer): Auf einer Pyramide des DOM (tiefste Zelle jedes 2×2-Blocks, bis zur groben Zellgröße des Parametersatzes) wird das Gelände Stufe für Stufe von grob nach fein prädiziert. Auf jeder Stufe wird ein Trend (eine robuste Ebene, danach das DGM der gröberen Stufe) abgezogen, eine Gauß-Kovarianz (Signalvarianz, Rauschanteil, Korrelationslänge) aus den Daten geschätzt und die Höhen werden mit Filterung prädiziert; robuste Iterationen geben Zellen unter der Fläche volles Gewicht und Zellen darüber weniger (null oberhalb der Abschneidegrenze), sodass die Fläche auf den Boden sinkt und Gebäude und Wälder überbrückt werden. Ausschlussgebiete „keep“ übernehmen das DOM als DGM, „remove“-Gebiete werden überbrückt, manuelle Bodenpunkte sind harte Bedingungen und Bruchkanten verhindern, dass die Prädiktion über sie hinweg reicht. Schreibt dtm.tif, ndsm.tif, mask.tif oder labels.txt, report.json/html und wahlweise das DGM jeder Stufe.</translation>
        </message>
        <message>
            <source>Coarsest pyramid cell [m]</source>
            <extracomment>filter_linear_prediction.coarse_spacing: description</extracomment>
            <translation>Gröbste Pyramidenzelle [m]</translation>
        </message>
        <message>
            <source>About the width of the largest building or wood to bridge.</source>
            <extracomment>filter_linear_prediction.coarse_spacing: help</extracomment>
            <translation>Etwa die Breite des größten zu überbrückenden Gebäudes oder Waldstücks.</translation>
        </message>
        <message>
            <source>Weight cut-off above the surface [m]</source>
            <extracomment>filter_linear_prediction.cutoff: description</extracomment>
            <translation>Gewichtsgrenze über der Fläche [m]</translation>
        </message>
        <message>
            <source>Cells more than this above the predicted surface (plus its shift) get weight 0 (objects).</source>
            <extracomment>filter_linear_prediction.cutoff: help</extracomment>
            <translation>Zellen, die mehr als dies über der prädizierten Fläche (plus ihrer Verschiebung) liegen, erhalten das Gewicht 0 (Objekte).</translation>
        </message>
        <message>
            <source>Half-weight residual [m]</source>
            <extracomment>filter_linear_prediction.half_weight: description</extracomment>
            <translation>Residuum bei halbem Gewicht [m]</translation>
        </message>
        <message>
            <source>Residual above the surface at which a cell keeps half its weight.</source>
            <extracomment>filter_linear_prediction.half_weight: help</extracomment>
            <translation>Residuum über der Fläche, bei dem eine Zelle die Hälfte ihres Gewichts behält.</translation>
        </message>
        <message>
            <source>Widens the cut-off and the candidate band at coarse levels by slope × cell/2, so hill tops and embankment edges are not cut.</source>
            <extracomment>filter_linear_prediction.slope: help</extracomment>
            <translation>Erweitert die Gewichtsgrenze und das Kandidatenband auf groben Stufen um Neigung × Zelle/2, damit Kuppen und Dammkanten nicht abgeschnitten werden.</translation>
        </message>
        <message>
            <source>Noise share (0 = pure interpolation)</source>
            <extracomment>filter_linear_prediction.noise_share: description</extracomment>
            <translation>Rauschanteil (0 = reine Interpolation)</translation>
        </message>
        <message>
            <source>Fixed σ²_noise / variance; empty = estimated from the data.</source>
            <extracomment>filter_linear_prediction.noise_share: help</extracomment>
            <translation>Fester Anteil σ²_Rauschen / Varianz; leer = aus den Daten geschätzt.</translation>
        </message>
        <message>
            <source>Robust iterations per level</source>
            <extracomment>filter_linear_prediction.iterations: description</extracomment>
            <translation>Robuste Iterationen je Stufe</translation>
        </message>
        <message>
            <source>Ground tolerance [m]</source>
            <extracomment>filter_linear_prediction.ground_tolerance: description</extracomment>
            <translation>Bodentoleranz [m]</translation>
        </message>
        <message>
            <source>Cells and points within this of the DTM are labelled ground.</source>
            <extracomment>filter_linear_prediction.ground_tolerance: help</extracomment>
            <translation>Zellen und Punkte, die höchstens so weit vom DGM abweichen, gelten als Boden.</translation>
        </message>
        <message>
            <source>Write the DTM of every pyramid level</source>
            <extracomment>filter_linear_prediction.write_levels: description</extracomment>
            <translation>DGM jeder Pyramidenstufe schreiben</translation>
        </message>
        <message>
            <source>Writes level_0.tif … level_k.tif for inspection.</source>
            <extracomment>filter_linear_prediction.write_levels: help</extracomment>
            <translation>Schreibt level_0.tif … level_k.tif zur Kontrolle.</translation>
        </message>
        <message>
            <source>Eliminated share, covariance per level, ground-point check</source>
            <extracomment>filter_linear_prediction output metrics</extracomment>
            <translation>Eliminierter Anteil, Kovarianz je Stufe, Prüfung der Bodenpunkte</translation>
        </message>
        <message>
            <source>Orthorectify image</source>
            <extracomment>orthorectify: name</extracomment>
            <translation>Bild orthorektifizieren</translation>
        </message>
        <message>
            <source>Orthophotos</source>
            <extracomment>mosaic: group; ortho_displacement: group; orthorectify: group; plugin/widgets/batch_dialog.py:173</extracomment>
            <translation>Orthofotos</translation>
        </message>
        <message>
            <source>Indirect differential rectification of one image of the project onto a DEM: for every output cell the height comes from the DEM (bilinear), the cell is projected into the image by the collinearity equations (with distortion) and the image is resampled there (nearest, bilinear or cubic), tile by tile. A DTM gives a classical ortho (buildings lean away from the nadir by Δr = h·r/H); a true ortho needs the DSM: cells the camera cannot see because a building or tree hides them are marked occluded (alpha 0, visibility 2) so that a mosaic fills them from another image. Writes a Cloud-Optimised GeoTIFF (COG) with overviews (the image bands plus an alpha band) and &lt;name&gt;_visibility.tif (0 outside the image, 1 visible, 2 occluded). A DEM in another CRS is reprojected on the fly (with a warning).</source>
            <extracomment>orthorectify: help</extracomment>
            <translation>Indirekte differentielle Entzerrung eines Bildes des Projekts auf ein DGM: Für jede Ausgabezelle kommt die Höhe aus dem DGM (bilinear), die Zelle wird mit den Kollinearitätsgleichungen (mit Verzeichnung) ins Bild projiziert und das Bild dort neu abgetastet (nächster Nachbar, bilinear oder kubisch), Kachel für Kachel. Ein DGM ergibt ein klassisches Orthofoto (Gebäude kippen um Δr = h·r/H vom Nadir weg); ein True-Ortho braucht das DOM: Zellen, die die Kamera nicht sieht, weil ein Gebäude oder Baum sie verdeckt, werden als verdeckt markiert (Alpha 0, Sichtbarkeit 2), damit ein Mosaik sie aus einem anderen Bild füllt. Schreibt ein Cloud-Optimised GeoTIFF (COG) mit Übersichten (die Bildkanäle plus ein Alphakanal) und &lt;name&gt;_visibility.tif (0 außerhalb des Bildes, 1 sichtbar, 2 verdeckt). Ein DGM in einem anderen KBS wird während der Verarbeitung umprojiziert (mit einer Warnung).</translation>
        </message>
        <message>
            <source>Image</source>
            <extracomment>ortho_displacement.image: description; orthorectify.image: description</extracomment>
            <translation>Bild</translation>
        </message>
        <message>
            <source>DEM (DTM, or DSM for a true ortho)</source>
            <extracomment>orthorectify.dem: description</extracomment>
            <translation>DHM (DGM, oder DOM für ein True-Ortho)</translation>
        </message>
        <message>
            <source>Heights of the surface to rectify onto; any CRS (reprojected on the fly).</source>
            <extracomment>orthorectify.dem: help</extracomment>
            <translation>Höhen der Fläche, auf die entzerrt wird; beliebiges KBS (wird bei Bedarf umprojiziert).</translation>
        </message>
        <message>
            <source>Orthophoto</source>
            <extracomment>orthorectify output ortho; orthorectify.output: description</extracomment>
            <translation>Orthofoto</translation>
        </message>
        <message>
            <source>Default: &lt;project&gt;/products/ortho/&lt;image&gt;.tif.</source>
            <extracomment>orthorectify.output: help</extracomment>
            <translation>Standard: &lt;project&gt;/products/ortho/&lt;image&gt;.tif.</translation>
        </message>
        <message>
            <source>Cell size (GSD) [m]</source>
            <extracomment>mosaic.gsd: description; orthorectify.gsd: description</extracomment>
            <translation>Zellgröße (Bodenauflösung) [m]</translation>
        </message>
        <message>
            <source>Default: the image's ground sample distance at the DEM's mean height, rounded.</source>
            <extracomment>orthorectify.gsd: help</extracomment>
            <translation>Höhen der Fläche, auf die entzerrt wird; beliebiges KBS (wird bei Bedarf umprojiziert).</translation>
        </message>
        <message>
            <source>Resampling</source>
            <extracomment>orthorectify.resampling: description</extracomment>
            <translation>Resampling</translation>
        </message>
        <message>
            <source>nearest</source>
            <extracomment>mosaic.resampling: option; orthorectify.resampling: option</extracomment>
            <translation>nächster Nachbar</translation>
        </message>
        <message>
            <source>bilinear</source>
            <extracomment>mosaic.resampling: option; orthorectify.resampling: option</extracomment>
            <translation>bilinear</translation>
        </message>
        <message>
            <source>cubic</source>
            <extracomment>mosaic.resampling: option; orthorectify.resampling: option</extracomment>
            <translation>kubisch</translation>
        </message>
        <message>
            <source>True ortho (occlusion test)</source>
            <extracomment>orthorectify.true_ortho: description</extracomment>
            <translation>Resampling</translation>
        </message>
        <message>
            <source>Mask cells hidden from the camera by the DSM; needs the DSM.</source>
            <extracomment>orthorectify.true_ortho: help</extracomment>
            <translation>Zellen maskieren, die das DOM vor der Kamera verdeckt; benötigt das DOM.</translation>
        </message>
        <message>
            <source>DSM for the occlusion test</source>
            <extracomment>orthorectify.dsm: description</extracomment>
            <translation>DOM für den Verdeckungstest</translation>
        </message>
        <message>
            <source>Needed for a true ortho; the DEM should then be this DSM too.</source>
            <extracomment>orthorectify.dsm: help</extracomment>
            <translation>Nötig für ein True-Ortho; als DHM sollte dann ebenfalls dieses DOM dienen.</translation>
        </message>
        <message>
            <source>Extent</source>
            <extracomment>orthorectify.extent: description</extracomment>
            <translation>Ausdehnung</translation>
        </message>
        <message>
            <source>xmin,ymin,xmax,ymax in the project CRS. Default: the image footprint on the DEM.</source>
            <extracomment>orthorectify.extent: help</extracomment>
            <translation>xmin,ymin,xmax,ymax im Projekt-KBS. Standard: der Bildfußabdruck auf dem DHM.</translation>
        </message>
        <message>
            <source>Visibility (0 outside, 1 visible, 2 occluded)</source>
            <extracomment>orthorectify output visibility</extracomment>
            <translation>Sichtbarkeit (0 außerhalb, 1 sichtbar, 2 verdeckt)</translation>
        </message>
        <message>
            <source>Cell size (m)</source>
            <extracomment>mosaic output gsd; orthorectify output gsd</extracomment>
            <translation>Zellgröße (m)</translation>
        </message>
        <message>
            <source>Occluded cells (% of the cells inside the image)</source>
            <extracomment>orthorectify output occluded_pct</extracomment>
            <translation>Zellen maskieren, die das DOM vor der Kamera verdeckt; benötigt das DOM.</translation>
        </message>
        <message>
            <source>Size [width, height] (cells)</source>
            <extracomment>mosaic output cells; orthorectify output cells</extracomment>
            <translation>Größe [Breite, Höhe] (Zellen)</translation>
        </message>
        <message>
            <source>Ortho displacement from DEM errors</source>
            <extracomment>ortho_displacement: name</extracomment>
            <translation>Orthofoto-Versatz durch DGM-Fehler</translation>
        </message>
        <message>
            <source>Shows where a DEM error moves an orthophoto. Predicted: for an image of the project and a DEM error e = DEM − reference (a difference raster, or the DEM and the reference DEM) the exact ray geometry gives the displacement d = −e·(X − X0, Y − Y0)/(Z0 − Zref), |d| = ΔR = Δh·R/H (R: distance from the nadir point, H: flying height above the cell); written as displacement.tif (|d|, dx, dy and the signed radial part, m, + away from the nadir). Measured: two orthos of the same area are matched in windows on a grid (NCC search, then least-squares refinement to a fraction of a pixel); shifts.gpkg and shifts.csv hold dx, dy (m and px), NCC and a status per window, summary.json the mean and RMS shift. With both, the predicted shift is added to every window.</source>
            <extracomment>ortho_displacement: help</extracomment>
            <translation>Zeigt, wohin ein DGM-Fehler ein Orthofoto verschiebt. Vorhergesagt: für ein Bild des Projekts und einen DGM-Fehler e = DGM − Referenz (ein Differenzraster, oder das DGM und das Referenz-DGM) ergibt die exakte Strahlgeometrie den Versatz d = −e·(X − X0, Y − Y0)/(Z0 − Zref), |d| = ΔR = Δh·R/H (R: Abstand vom Nadirpunkt, H: Flughöhe über der Zelle); geschrieben als displacement.tif (|d|, dx, dy und der vorzeichenbehaftete radiale Anteil, m, + vom Nadir weg). Gemessen: zwei Orthofotos desselben Gebiets werden in Fenstern auf einem Raster zugeordnet (NCC-Suche, dann Kleinste-Quadrate-Verfeinerung auf Bruchteile eines Pixels); shifts.gpkg und shifts.csv enthalten dx, dy (m und px), NCC und einen Status je Fenster, summary.json die mittlere und die RMS-Verschiebung. Mit beidem wird jedem Fenster die vorhergesagte Verschiebung beigefügt.</translation>
        </message>
        <message>
            <source>Needed for the predicted displacement.</source>
            <extracomment>ortho_displacement.project: help</extracomment>
            <translation>Nötig für den vorhergesagten Versatz.</translation>
        </message>
        <message>
            <source>The image whose ortho is analysed (predicted displacement).</source>
            <extracomment>ortho_displacement.image: help</extracomment>
            <translation>Das Bild, dessen Orthofoto untersucht wird (vorhergesagter Versatz).</translation>
        </message>
        <message>
            <source>DEM error (DEM − reference) [m]</source>
            <extracomment>ortho_displacement.error: description</extracomment>
            <translation>DGM-Fehler (DGM − Referenz) [m]</translation>
        </message>
        <message>
            <source>E.g. difference.tif of 'Compare DEM with reference'; its grid is the output grid.</source>
            <extracomment>ortho_displacement.error: help</extracomment>
            <translation>Z. B. difference.tif aus „DGM mit Referenz vergleichen“; sein Raster ist das Ausgaberaster.</translation>
        </message>
        <message>
            <source>DEM of the ortho</source>
            <extracomment>ortho_displacement.dem: description</extracomment>
            <translation>DGM des Orthofotos</translation>
        </message>
        <message>
            <source>With the reference DEM instead of an error raster: e = DEM − reference on the DEM's grid.</source>
            <extracomment>ortho_displacement.dem: help</extracomment>
            <translation>Mit dem Referenz-DGM statt eines Fehlerrasters: e = DGM − Referenz auf dem Raster des DGM.</translation>
        </message>
        <message>
            <source>Reference DEM (true heights)</source>
            <extracomment>ortho_displacement.reference: description</extracomment>
            <translation>Referenz-DGM (wahre Höhen)</translation>
        </message>
        <message>
            <source>Terrain height [m]</source>
            <extracomment>ortho_displacement.terrain_height: description</extracomment>
            <translation>Geländehöhe [m]</translation>
        </message>
        <message>
            <source>True height for H when only the error raster is given (default: the project's terrain height).</source>
            <extracomment>ortho_displacement.terrain_height: help</extracomment>
            <translation>Wahre Höhe für H, wenn nur das Fehlerraster gegeben ist (Standard: die Geländehöhe des Projekts).</translation>
        </message>
        <message>
            <source>Ortho to check</source>
            <extracomment>ortho_displacement.ortho: description</extracomment>
            <translation>Zu prüfendes Orthofoto</translation>
        </message>
        <message>
            <source>Measured shift: this ortho is matched against the reference ortho.</source>
            <extracomment>ortho_displacement.ortho: help</extracomment>
            <translation>Gemessene Verschiebung: dieses Orthofoto wird dem Referenz-Orthofoto zugeordnet.</translation>
        </message>
        <message>
            <source>Reference ortho</source>
            <extracomment>ortho_displacement.reference_ortho: description</extracomment>
            <translation>Referenz-Orthofoto</translation>
        </message>
        <message>
            <source>Its grid defines the windows and the pixel unit (e.g. the ortho on the reference DEM, or a neighbouring ortho).</source>
            <extracomment>ortho_displacement.reference_ortho: help</extracomment>
            <translation>Sein Raster bestimmt die Fenster und die Pixeleinheit (z. B. das Orthofoto auf dem Referenz-DGM oder ein benachbartes Orthofoto).</translation>
        </message>
        <message>
            <source>Matching window [px]</source>
            <extracomment>ortho_displacement.window: description</extracomment>
            <translation>Zuordnungsfenster [px]</translation>
        </message>
        <message>
            <source>Odd size of the matched windows.</source>
            <extracomment>ortho_displacement.window: help</extracomment>
            <translation>Ungerade Größe der zugeordneten Fenster.</translation>
        </message>
        <message>
            <source>Search radius [px]</source>
            <extracomment>ortho_displacement.radius: description</extracomment>
            <translation>Suchradius [px]</translation>
        </message>
        <message>
            <source>Largest shift that is searched for.</source>
            <extracomment>ortho_displacement.radius: help</extracomment>
            <translation>Größte Verschiebung, nach der gesucht wird.</translation>
        </message>
        <message>
            <source>Window spacing [px]</source>
            <extracomment>ortho_displacement.spacing: description</extracomment>
            <translation>Fensterabstand [px]</translation>
        </message>
        <message>
            <source>Default: the window size.</source>
            <extracomment>ortho_displacement.spacing: help</extracomment>
            <translation>Standard: die Fenstergröße.</translation>
        </message>
        <message>
            <source>Minimum correlation</source>
            <extracomment>ortho_displacement.min_ncc: description</extracomment>
            <translation>Mindestkorrelation</translation>
        </message>
        <message>
            <source>Receives displacement.tif, shifts.gpkg, shifts.csv and summary.json.</source>
            <extracomment>ortho_displacement.output: help</extracomment>
            <translation>Erhält displacement.tif, shifts.gpkg, shifts.csv und summary.json.</translation>
        </message>
        <message>
            <source>Predicted displacement (|d|, dx, dy, radial) [m]</source>
            <extracomment>ortho_displacement output displacement</extracomment>
            <translation>Vorhergesagter Versatz (|d|, dx, dy, radial) [m]</translation>
        </message>
        <message>
            <source>Statistics of the predicted displacement</source>
            <extracomment>ortho_displacement output predicted</extracomment>
            <translation>Statistik des vorhergesagten Versatzes</translation>
        </message>
        <message>
            <source>Measured shifts per window (GeoPackage)</source>
            <extracomment>ortho_displacement output points</extracomment>
            <translation>Gemessene Verschiebungen je Fenster (GeoPackage)</translation>
        </message>
        <message>
            <source>Measured shifts per window (CSV)</source>
            <extracomment>ortho_displacement output csv</extracomment>
            <translation>Gemessene Verschiebungen je Fenster (CSV)</translation>
        </message>
        <message>
            <source>Statistics of the measured shifts</source>
            <extracomment>ortho_displacement output measured</extracomment>
            <translation>Statistik der gemessenen Verschiebungen</translation>
        </message>
        <message>
            <source>Measured against predicted shifts</source>
            <extracomment>ortho_displacement output comparison</extracomment>
            <translation>Gemessene gegen vorhergesagte Verschiebungen</translation>
        </message>
        <message>
            <source>Summary (JSON)</source>
            <extracomment>ortho_displacement output json</extracomment>
            <translation>Zusammenfassung (JSON)</translation>
        </message>
        <message>
            <source>Orthophoto mosaic</source>
            <extracomment>mosaic: name</extracomment>
            <translation>Orthophotomosaik</translation>
        </message>
        <message>
            <source>Mosaics orthos into one Cloud-Optimised GeoTIFF (COG) with overviews (colour bands + alpha). Inputs: orthos (PhotoDEM orthos carry their projection centre), or a project and a DEM: then every image is rectified first (a true ortho on the DSM with true_ortho). Seamlines: auto starts from the nadir partition (each cell to the image with the nearest projection centre) and routes every seam along a least-cost path through low image difference and low DSM height above the DTM (give dsm and dtm), so seams do not cut through buildings or trees; nadir keeps the partition; edits takes the 'seamlines' layer of the project's edits.gpkg; or give a vector file: lines cut the area (each part to the image nearest in nadir), polygons with an 'image' attribute take their area from that image (the footprints layer a mosaic writes can be edited and reused). Occluded cells (alpha 0) are filled from the next best image. Balancing: gain and offset per image and band by least squares over all overlaps (gain_offset), plus histogram matching (histogram), or none; feathering blends across seams over the given width. Writes the mosaic, &lt;name&gt;_seamlines.gpkg (footprints: one polygon per source image; seamlines) and &lt;name&gt;_balance.json (gains, offsets, mean difference of the overlaps before and after). Works tile by tile; seams and balancing use a seam grid of at most seam_cells cells a side, so memory does not grow with the mosaic.</source>
            <extracomment>mosaic: help</extracomment>
            <translation>Fügt Orthophotos zu einem Cloud-Optimised GeoTIFF (COG) mit Übersichten zusammen (Farbkanäle + Alpha). Eingaben: Orthophotos (PhotoDEM-Orthophotos tragen ihr Projektionszentrum) oder ein Projekt und ein DGM: dann wird zuerst jedes Bild entzerrt (mit true_ortho ein True-Ortho auf dem DOM). Schnittlinien: auto beginnt mit der Nadir-Aufteilung (jede Zelle zum Bild mit dem nächsten Projektionszentrum) und führt jede Schnittlinie auf einem Weg geringster Kosten durch geringe Bilddifferenz und geringe Höhe des DOM über dem DGM (dsm und dtm angeben), sodass Schnittlinien keine Gebäude oder Bäume zerschneiden; nadir behält die Aufteilung; edits nimmt die Ebene 'seamlines' der edits.gpkg des Projekts; oder eine Vektordatei angeben: Linien zerschneiden die Fläche (jeder Teil zum im Nadir nächsten Bild), Polygone mit einem Attribut 'image' nehmen ihre Fläche aus diesem Bild (die Ebene footprints, die ein Mosaik schreibt, kann bearbeitet und wiederverwendet werden). Verdeckte Zellen (Alpha 0) werden aus dem nächstbesten Bild gefüllt. Ausgleich: Verstärkung und Versatz je Bild und Kanal durch Ausgleichung über alle Überlappungen (gain_offset), zusätzlich Histogrammanpassung (histogram) oder keiner; Überblendung über die angegebene Breite an den Schnittlinien. Schreibt das Mosaik, &lt;Name&gt;_seamlines.gpkg (footprints: ein Polygon je Quellbild; seamlines) und &lt;Name&gt;_balance.json (Verstärkungen, Versätze, mittlere Differenz der Überlappungen vorher und nachher). Arbeitet kachelweise; Schnittlinien und Ausgleich nutzen ein Schnittliniengitter mit höchstens seam_cells Zellen je Seite, sodass der Speicherbedarf nicht mit dem Mosaik wächst.</translation>
        </message>
        <message>
            <source>Needed with 'dem' (rectify every image) and for seamlines=edits.</source>
            <extracomment>mosaic.project: help</extracomment>
            <translation>Nötig mit 'dem' (jedes Bild entzerren) und für seamlines=edits.</translation>
        </message>
        <message>
            <source>Orthos</source>
            <extracomment>mosaic.inputs: description</extracomment>
            <translation>Orthophotos</translation>
        </message>
        <message>
            <source>Orthos to mosaic (same CRS, bands and data type).</source>
            <extracomment>mosaic.inputs: help</extracomment>
            <translation>Zu mosaikierende Orthophotos (gleiches KBS, gleiche Kanäle und gleicher Datentyp).</translation>
        </message>
        <message>
            <source>DEM to rectify the project images on</source>
            <extracomment>mosaic.dem: description</extracomment>
            <translation>DGM zur Entzerrung der Projektbilder</translation>
        </message>
        <message>
            <source>Instead of 'inputs': every image of the project is rectified onto it.</source>
            <extracomment>mosaic.dem: help</extracomment>
            <translation>Statt 'inputs': jedes Bild des Projekts wird darauf entzerrt.</translation>
        </message>
        <message>
            <source>True orthos (occlusion test)</source>
            <extracomment>mosaic.true_ortho: description</extracomment>
            <translation>True-Orthos (Verdeckungstest)</translation>
        </message>
        <message>
            <source>With 'dem': rectify on the DSM with the occlusion test; needs 'dsm'.</source>
            <extracomment>mosaic.true_ortho: help</extracomment>
            <translation>Mit 'dem': auf dem DOM mit Verdeckungstest entzerren; benötigt 'dsm'.</translation>
        </message>
        <message>
            <source>Surface for true orthos and, with the DTM, for seams that avoid buildings and trees.</source>
            <extracomment>mosaic.dsm: help</extracomment>
            <translation>Oberfläche für True-Orthos und, mit dem DGM, für Schnittlinien, die Gebäude und Bäume meiden.</translation>
        </message>
        <message>
            <source>Terrain for the height above ground (DSM − DTM) of the seam cost. Default with 'dem': the DEM when it is not the DSM.</source>
            <extracomment>mosaic.dtm: help</extracomment>
            <translation>Gelände für die Höhe über Grund (DOM − DGM) in den Schnittlinienkosten. Standard mit 'dem': das DGM, wenn es nicht das DOM ist.</translation>
        </message>
        <message>
            <source>Default: the finest input (or the images' GSD when rectifying).</source>
            <extracomment>mosaic.gsd: help</extracomment>
            <translation>Standard: die feinste Eingabe (bzw. die Bodenauflösung der Bilder beim Entzerren).</translation>
        </message>
        <message>
            <source>Resampling (rectification)</source>
            <extracomment>mosaic.resampling: description</extracomment>
            <translation>Resampling (Entzerrung)</translation>
        </message>
        <message>
            <source>Seamlines</source>
            <extracomment>mosaic.seamlines: description; plugin/app/map_window.py:457; plugin/qgis/workspace.py:410; plugin/qgis/workspace.py:427; plugin/widgets/edit_session.py:359</extracomment>
            <translation>Schnittlinien</translation>
        </message>
        <message>
            <source>auto, nadir, edits, or a vector file (lines, or polygons with an 'image' attribute).</source>
            <extracomment>mosaic.seamlines: help</extracomment>
            <translation>auto, nadir, edits oder eine Vektordatei (Linien oder Polygone mit einem Attribut 'image').</translation>
        </message>
        <message>
            <source>Radiometric balancing</source>
            <extracomment>mosaic.balance: description</extracomment>
            <translation>Radiometrischer Ausgleich</translation>
        </message>
        <message>
            <source>none</source>
            <extracomment>algorithms/processing/batch.py:403; mosaic.balance: option</extracomment>
            <translation>keiner</translation>
        </message>
        <message>
            <source>gain_offset</source>
            <extracomment>mosaic.balance: option</extracomment>
            <translation>Verstärkung/Versatz</translation>
        </message>
        <message>
            <source>histogram</source>
            <extracomment>mosaic.balance: option</extracomment>
            <translation>Histogrammanpassung</translation>
        </message>
        <message>
            <source>Reference image</source>
            <extracomment>mosaic.reference: description</extracomment>
            <translation>Referenzbild</translation>
        </message>
        <message>
            <source>Image kept unchanged by the balancing. Default: mean gain 1, mean offset 0.</source>
            <extracomment>mosaic.reference: help</extracomment>
            <translation>Bild, das der Ausgleich unverändert lässt. Standard: mittlere Verstärkung 1, mittlerer Versatz 0.</translation>
        </message>
        <message>
            <source>Feather width [m]</source>
            <extracomment>mosaic.feather: description</extracomment>
            <translation>Überblendbreite [m]</translation>
        </message>
        <message>
            <source>Blend width across seams. Default: 10 cells; 0 = hard.</source>
            <extracomment>mosaic.feather: help</extracomment>
            <translation>Breite der Überblendung über die Schnittlinien. Standard: 10 Zellen; 0 = harter Schnitt.</translation>
        </message>
        <message>
            <source>Seam corridor half-width [m]</source>
            <extracomment>mosaic.corridor: description</extracomment>
            <translation>Halbe Breite des Schnittlinienkorridors [m]</translation>
        </message>
        <message>
            <source>How far a seam may leave the nadir boundary. Default: a quarter of the distance between neighbouring projection centres.</source>
            <extracomment>mosaic.corridor: help</extracomment>
            <translation>Wie weit eine Schnittlinie von der Nadirgrenze abweichen darf. Standard: ein Viertel des Abstands benachbarter Projektionszentren.</translation>
        </message>
        <message>
            <source>Cells at least this high above the DTM are avoided by seams.</source>
            <extracomment>mosaic.min_height: help</extracomment>
            <translation>Zellen mindestens so hoch über dem DGM meiden die Schnittlinien.</translation>
        </message>
        <message>
            <source>Side of the processing tiles.</source>
            <extracomment>mosaic.tile: help</extracomment>
            <translation>Seitenlänge der Verarbeitungskacheln.</translation>
        </message>
        <message>
            <source>Seam grid size [cells]</source>
            <extracomment>mosaic.seam_cells: description</extracomment>
            <translation>Größe des Schnittliniengitters [Zellen]</translation>
        </message>
        <message>
            <source>Longest side of the reduced grid for seams and balancing.</source>
            <extracomment>mosaic.seam_cells: help</extracomment>
            <translation>Längste Seite des verkleinerten Gitters für Schnittlinien und Ausgleich.</translation>
        </message>
        <message>
            <source>Mosaic</source>
            <extracomment>mosaic output mosaic; mosaic.output: description; plugin/app/map_window.py:457; plugin/qgis/workspace.py:427</extracomment>
            <translation>Mosaik</translation>
        </message>
        <message>
            <source>Default: &lt;project&gt;/products/mosaic/mosaic.tif.</source>
            <extracomment>mosaic.output: help</extracomment>
            <translation>Standard: &lt;Projekt&gt;/products/mosaic/mosaic.tif.</translation>
        </message>
        <message>
            <source>Footprints and seamlines (GeoPackage)</source>
            <extracomment>mosaic output seamlines</extracomment>
            <translation>Bildflächen und Schnittlinien (GeoPackage)</translation>
        </message>
        <message>
            <source>Balancing report (JSON)</source>
            <extracomment>mosaic output report</extracomment>
            <translation>Ausgleichsbericht (JSON)</translation>
        </message>
        <message>
            <source>Seam statistics</source>
            <extracomment>mosaic output seams</extracomment>
            <translation>Schnittlinienstatistik</translation>
        </message>
        <message>
            <source>Mean difference in the overlaps before/after balancing</source>
            <extracomment>mosaic output balance</extracomment>
            <translation>Mittlere Differenz in den Überlappungen vor/nach dem Ausgleich</translation>
        </message>
        <message>
            <source>Georeference image against polygons</source>
            <extracomment>georeference_polygons: name</extracomment>
            <translation>Bild an Polygonen georeferenzieren</translation>
        </message>
        <message>
            <source>Georeferencing</source>
            <extracomment>georeference_polygons: group</extracomment>
            <translation>Georeferenzierung</translation>
        </message>
        <message>
            <source>Finds the georeference of an image without approximate values (position, scale, rotation and mirroring unknown) by matching area objects: the image is segmented by region growing at several thresholds, its regions and the reference polygons (one class of a vector layer, touching polygons dissolved — or a segmented orthophoto) are described by affine-invariant moment features, corresponding objects are found by a consistency search, verified, refined by ICP, and control points on their outlines give the final transform (affine, projective or 2nd-order polynomial). When no objects match (objects not homogeneous in the image), an area-based search compares the whole image with the rasterised polygons, or the polygons' individual outlines with the image's edge directions, instead. Writes a QGIS Georeferencer .points file, the control points as GeoPackage, the image resampled into the map CRS, a copy with the control points embedded and a report (overlay, residuals, RMSE in px and m). Too few matching objects give a failure message with the counts of every stage, not a wrong result.</source>
            <extracomment>georeference_polygons: help</extracomment>
            <translation>Bestimmt die Georeferenz eines Bildes ohne Näherungswerte (Position, Maßstab, Drehung und Spiegelung unbekannt) durch Zuordnung von Flächenobjekten: Das Bild wird mit mehreren Schwellen durch Bereichswachstum segmentiert, seine Regionen und die Referenzpolygone (eine Klasse eines Vektorlayers, aneinandergrenzende Polygone verschmolzen — oder ein segmentiertes Orthophoto) werden durch affin-invariante Momentmerkmale beschrieben, zugehörige Objekte durch eine Konsistenzsuche gefunden, verifiziert und mit ICP verfeinert; Passpunkte auf ihren Konturen ergeben die endgültige Transformation (affin, projektiv oder Polynom 2. Grades). Passen keine Objekte zusammen (Objekte im Bild nicht homogen), vergleicht stattdessen eine flächenbasierte Suche das ganze Bild mit den gerasterten Polygonen oder die einzelnen Umrisse der Polygone mit den Kantenrichtungen des Bildes. Schreibt eine .points-Datei des QGIS-Georeferenzierers, die Passpunkte als GeoPackage, das in das Karten-KBS umgebildete Bild, eine Kopie mit eingebetteten Passpunkten und einen Bericht (Überlagerung, Residuen, RMSE in px und m). Zu wenige zugeordnete Objekte ergeben eine Fehlermeldung mit den Anzahlen jeder Stufe, kein falsches Ergebnis.</translation>
        </message>
        <message>
            <source>Image to georeference</source>
            <extracomment>georeference_polygons.image: description</extracomment>
            <translation>Zu georeferenzierendes Bild</translation>
        </message>
        <message>
            <source>Any band count (default: the mean of the bands); its own georeference, if any, is ignored.</source>
            <extracomment>georeference_polygons.image: help</extracomment>
            <translation>Beliebige Kanalzahl (Standard: Mittel der Kanäle); eine eigene Georeferenz des Bildes wird nicht verwendet.</translation>
        </message>
        <message>
            <source>Reference (polygon layer or orthophoto)</source>
            <extracomment>georeference_polygons.reference: description</extracomment>
            <translation>Referenz (Polygonlayer oder Orthophoto)</translation>
        </message>
        <message>
            <source>A polygon layer in any CRS (matched in its projected CRS, or the UTM zone of its centre), or a georeferenced raster (an orthophoto or satellite scene in a projected CRS): matched by keypoints first, else segmented like the image.</source>
            <extracomment>georeference_polygons.reference: help</extracomment>
            <translation>Ein Polygonlayer in beliebigem KBS (zugeordnet in seinem projizierten KBS oder in der UTM-Zone seiner Mitte) oder ein georeferenziertes Raster (ein Orthophoto oder eine Satellitenszene in einem projizierten KBS): zuerst über Merkmalspunkte zugeordnet, sonst wie das Bild segmentiert.</translation>
        </message>
        <message>
            <source>Class attribute</source>
            <extracomment>georeference_polygons.class_field: description; plugin/qgis/qc_dock.py:195</extracomment>
            <translation>Klassenattribut</translation>
        </message>
        <message>
            <source>Attribute selecting the polygons to match (e.g. landuse); empty = all polygons.</source>
            <extracomment>georeference_polygons.class_field: help</extracomment>
            <translation>Attribut, das die zuzuordnenden Polygone auswählt (z. B. landuse); leer = alle Polygone.</translation>
        </message>
        <message>
            <source>Class value</source>
            <extracomment>georeference_polygons.class_value: description</extracomment>
            <translation>Klassenwert</translation>
        </message>
        <message>
            <source>Value of the class attribute (e.g. forest).</source>
            <extracomment>georeference_polygons.class_value: help</extracomment>
            <translation>Wert des Klassenattributs (z. B. forest).</translation>
        </message>
        <message>
            <source>Transform</source>
            <extracomment>georeference_polygons.transform: description</extracomment>
            <translation>Transformation</translation>
        </message>
        <message>
            <source>affine</source>
            <extracomment>georeference_polygons.transform: option</extracomment>
            <translation>affin</translation>
        </message>
        <message>
            <source>projective</source>
            <extracomment>georeference_polygons.transform: option</extracomment>
            <translation>projektiv</translation>
        </message>
        <message>
            <source>poly2</source>
            <extracomment>georeference_polygons.transform: option</extracomment>
            <translation>Polynom 2. Grades</translation>
        </message>
        <message>
            <source>Segmentation thresholds [DN]</source>
            <extracomment>georeference_polygons.thresholds: description</extracomment>
            <translation>Segmentierungsschwellen [GW]</translation>
        </message>
        <message>
            <source>Region-growing thresholds in grey values of 8-bit data (other data are stretched to 0–255 first), small = over-segmentation.</source>
            <extracomment>georeference_polygons.thresholds: help</extracomment>
            <translation>Schwellen des Bereichswachstums in Grauwerten von 8-Bit-Daten (andere Daten werden zuerst auf 0–255 gestreckt); klein = Übersegmentierung.</translation>
        </message>
        <message>
            <source>Pyramid level (−1 = auto)</source>
            <extracomment>georeference_polygons.pyramid_level: description</extracomment>
            <translation>Pyramidenstufe (−1 = automatisch)</translation>
        </message>
        <message>
            <source>Segment this pyramid level (factor 2 each); auto: the first level with at most 4 Mpx.</source>
            <extracomment>georeference_polygons.pyramid_level: help</extracomment>
            <translation>Diese Pyramidenstufe segmentieren (Faktor 2 je Stufe); automatisch: die erste Stufe mit höchstens 4 Mpx.</translation>
        </message>
        <message>
            <source>Invariant tolerance [%]</source>
            <extracomment>georeference_polygons.relative_difference: description</extracomment>
            <translation>Toleranz der Invarianten [%]</translation>
        </message>
        <message>
            <source>Relative difference allowed for each of the six invariants.</source>
            <extracomment>georeference_polygons.relative_difference: help</extracomment>
            <translation>Zulässige relative Differenz für jede der sechs Invarianten.</translation>
        </message>
        <message>
            <source>Search depth [pairs]</source>
            <extracomment>georeference_polygons.max_depth: description</extracomment>
            <translation>Suchtiefe [Paare]</translation>
        </message>
        <message>
            <source>Search</source>
            <extracomment>georeference_polygons.search: description</extracomment>
            <translation>Suche</translation>
        </message>
        <message>
            <source>objects: match image regions to the polygons as objects; area: compare the whole image with the rasterised polygons (rotation and scale by Fourier–Mellin, shift by correlation, refined by ECC), and when that fails the polygons' individual outlines with the image's edge directions — for objects that are not homogeneous in the image, such as glaciers (polygon layers only); keypoints: SIFT keypoints of the image and the mirrored image matched to a raster reference, refined by correlating image patches (raster references only); auto: for polygons objects, then the area-based search; for a raster keypoints, then objects.</source>
            <extracomment>georeference_polygons.search: help</extracomment>
            <translation>objects: Bildregionen als Objekte den Polygonen zuordnen; area: das ganze Bild mit den gerasterten Polygonen vergleichen (Drehung und Maßstab nach Fourier–Mellin, Verschiebung durch Korrelation, Verfeinerung mit ECC) und, wenn das scheitert, die einzelnen Umrisse der Polygone mit den Kantenrichtungen des Bildes — für Objekte, die im Bild nicht homogen sind, etwa Gletscher (nur Polygonlayer); keypoints: SIFT-Merkmalspunkte des Bildes und des gespiegelten Bildes einem Referenzraster zugeordnet, verfeinert durch Korrelation von Bildausschnitten (nur Referenzraster); auto: bei Polygonen Objekte, dann die flächenbasierte Suche; bei einem Raster Merkmalspunkte, dann Objekte.</translation>
        </message>
        <message>
            <source>objects</source>
            <extracomment>georeference_polygons.search: option</extracomment>
            <translation>Objekte</translation>
        </message>
        <message>
            <source>area</source>
            <extracomment>georeference_polygons.search: option</extracomment>
            <translation>Fläche</translation>
        </message>
        <message>
            <source>keypoints</source>
            <extracomment>georeference_polygons.search: option; plugin/widgets/georef_review.py:67</extracomment>
            <translation>Merkmalspunkte</translation>
        </message>
        <message>
            <source>Reference objects</source>
            <extracomment>georeference_polygons.objects: description</extracomment>
            <translation>Referenzobjekte</translation>
        </message>
        <message>
            <source>buildings: many small footprints (cadastre, OpenStreetMap) matched by the configuration of neighbouring buildings; areas: forests, fields, lakes, glaciers; auto: buildings when the layer has at least 15 mostly rectangular polygons whose median area is below 0.4 % of the layer's extent and below 5000 m².</source>
            <extracomment>georeference_polygons.objects: help</extracomment>
            <translation>buildings: viele kleine Gebäudegrundrisse (Kataster, OpenStreetMap), zugeordnet über die Anordnung benachbarter Gebäude; areas: Wälder, Felder, Seen, Gletscher; auto: Gebäude, wenn die Ebene mindestens 15 überwiegend rechteckige Polygone hat, deren mittlere Fläche (Median) unter 0,4 % der Ausdehnung der Ebene und unter 5000 m² liegt.</translation>
        </message>
        <message>
            <source>areas</source>
            <extracomment>georeference_polygons.objects: option</extracomment>
            <translation>Flächen</translation>
        </message>
        <message>
            <source>buildings</source>
            <extracomment>georeference_polygons.objects: option</extracomment>
            <translation>Gebäude</translation>
        </message>
        <message>
            <source>Control point tolerance σ_NP [px]</source>
            <extracomment>georeference_polygons.sigma_np: description</extracomment>
            <translation>Passpunkttoleranz σ_NP [px]</translation>
        </message>
        <message>
            <source>Control points are accepted (best first) while the RMS of their outline distances stays below this.</source>
            <extracomment>georeference_polygons.sigma_np: help</extracomment>
            <translation>Passpunkte werden (beste zuerst) übernommen, solange der RMS ihrer Konturabstände darunter bleibt.</translation>
        </message>
        <message>
            <source>Write an unverified result</source>
            <extracomment>georeference_polygons.unverified: description</extracomment>
            <translation>Unbestätigtes Ergebnis schreiben</translation>
        </message>
        <message>
            <source>A result is accepted only when independent evidence supports it: control points spread over the image, halves of them agreeing at the image corners, image and reference agreeing best at the result. Without that the run fails with the figures; with this option the result is written marked UNVERIFIED instead.</source>
            <extracomment>georeference_polygons.unverified: help</extracomment>
            <translation>Ein Ergebnis wird nur angenommen, wenn unabhängige Belege es stützen: über das Bild verteilte Passpunkte, an den Bildecken übereinstimmende Transformationen aus je einer Hälfte der Passpunkte, beste Übereinstimmung von Bild und Referenz genau beim Ergebnis. Fehlt das, bricht der Lauf mit den Kennzahlen ab; mit dieser Option wird das Ergebnis stattdessen als UNBESTÄTIGT gekennzeichnet geschrieben.</translation>
        </message>
        <message>
            <source>Time limit [s]</source>
            <extracomment>georeference_polygons.time_limit: description</extracomment>
            <translation>Zeitlimit [s]</translation>
        </message>
        <message>
            <source>The search stops when this time is spent and the run fails with the figures found so far (0: no limit).</source>
            <extracomment>georeference_polygons.time_limit: help</extracomment>
            <translation>Die Suche endet, wenn diese Zeit verbraucht ist, und der Lauf bricht mit den bis dahin gefundenen Kennzahlen ab (0: kein Limit).</translation>
        </message>
        <message>
            <source>Transform (kind, 3 × 3 matrix image col/row → map)</source>
            <extracomment>georeference_polygons output transform</extracomment>
            <translation>Transformation (Art, 3 × 3-Matrix Bildspalte/-zeile → Karte)</translation>
        </message>
        <message>
            <source>RMSE of the control points (px)</source>
            <extracomment>georeference_polygons output rmse_px</extracomment>
            <translation>RMSE der Passpunkte (px)</translation>
        </message>
        <message>
            <source>RMSE of the control points (map units)</source>
            <extracomment>georeference_polygons output rmse_m</extracomment>
            <translation>RMSE der Passpunkte (Karteneinheiten)</translation>
        </message>
        <message>
            <source>Control points (QGIS .points)</source>
            <extracomment>georeference_polygons output gcps</extracomment>
            <translation>Passpunkte (QGIS .points)</translation>
        </message>
        <message>
            <source>Control points (GeoPackage)</source>
            <extracomment>georeference_polygons output gcps_gpkg</extracomment>
            <translation>Passpunkte (GeoPackage)</translation>
        </message>
        <message>
            <source>Georeferenced image</source>
            <extracomment>georeference_polygons output image</extracomment>
            <translation>Georeferenziertes Bild</translation>
        </message>
        <message>
            <source>Report (JSON; HTML beside it)</source>
            <extracomment>georeference_polygons output report</extracomment>
            <translation>Bericht (JSON; HTML daneben)</translation>
        </message>
        <message>
            <source>Verified object pairs</source>
            <extracomment>georeference_polygons output n_pairs</extracomment>
            <translation>Verifizierte Objektpaare</translation>
        </message>
        <message>
            <source>Control points used</source>
            <extracomment>georeference_polygons output n_gcps</extracomment>
            <translation>Verwendete Passpunkte</translation>
        </message>
        <message>
            <source>Verified by independent evidence (yes/no)</source>
            <extracomment>georeference_polygons output verified</extracomment>
            <translation>Durch unabhängige Belege bestätigt (ja/nein)</translation>
        </message>
        <message>
            <source>QC area</source>
            <extracomment>plugin/app/docks.py:107</extracomment>
            <translation>Qualität: Fläche</translation>
        </message>
        <message>
            <source>QC profile</source>
            <extracomment>plugin/app/docks.py:108</extracomment>
            <translation>Qualität: Profil</translation>
        </message>
        <message>
            <source>QC identify</source>
            <extracomment>plugin/app/docks.py:110</extracomment>
            <translation>Qualität: Abfragen</translation>
        </message>
        <message>
            <source>Undo history</source>
            <extracomment>plugin/app/docks.py:141</extracomment>
            <translation>Bearbeitungsverlauf</translation>
        </message>
        <message>
            <source>DEM quality</source>
            <extracomment>plugin/app/docks.py:56</extracomment>
            <translation>DHM-Qualität</translation>
        </message>
        <message>
            <source>Batch</source>
            <extracomment>plugin/app/docks.py:78</extracomment>
            <translation>Batch</translation>
        </message>
        <message>
            <source>Blunder to {0}</source>
            <extracomment>plugin/app/docks.py:45; plugin/qgis/qc_dock.py:452</extracomment>
            <translation>Grober Fehler nach {0}</translation>
        </message>
        <message>
            <source>PhotoDEM toolbox</source>
            <extracomment>plugin/app/main_window.py:54</extracomment>
            <translation>PhotoDEM-Werkzeugkasten</translation>
        </message>
        <message>
            <source>Search algorithms …</source>
            <extracomment>plugin/app/main_window.py:64</extracomment>
            <translation>Algorithmen suchen …</translation>
        </message>
        <message>
            <source>Processing toolbox</source>
            <extracomment>plugin/app/main_window.py:128</extracomment>
            <translation>Processing-Werkzeugkasten</translation>
        </message>
        <message>
            <source>Open a project (File menu) or choose an algorithm in the toolbox.</source>
            <extracomment>plugin/app/main_window.py:135</extracomment>
            <translation>Öffnen Sie ein Projekt (Menü Datei) oder wählen Sie einen Algorithmus im Werkzeugkasten.</translation>
        </message>
        <message>
            <source>&amp;File</source>
            <extracomment>plugin/app/main_window.py:150</extracomment>
            <translation>&amp;Datei</translation>
        </message>
        <message>
            <source>&amp;View</source>
            <extracomment>plugin/app/main_window.py:151</extracomment>
            <translation>&amp;Ansicht</translation>
        </message>
        <message>
            <source>&amp;Quit</source>
            <extracomment>plugin/app/main_window.py:155</extracomment>
            <translation>&amp;Beenden</translation>
        </message>
        <message>
            <source>&amp;Tools</source>
            <extracomment>plugin/app/main_window.py:158</extracomment>
            <translation>&amp;Werkzeuge</translation>
        </message>
        <message>
            <source>Review georeferencing…</source>
            <extracomment>plugin/app/main_window.py:159; plugin/qgis/plugin.py:113</extracomment>
            <translation>Georeferenzierung prüfen…</translation>
        </message>
        <message>
            <source>Check and edit the control points of a georeferencing result</source>
            <extracomment>plugin/app/main_window.py:160; plugin/qgis/plugin.py:115</extracomment>
            <translation>Passpunkte eines Georeferenzierungsergebnisses prüfen und bearbeiten</translation>
        </message>
        <message>
            <source>Batch over stereo models…</source>
            <extracomment>plugin/app/main_window.py:164; plugin/qgis/batch_actions.py:127</extracomment>
            <translation>Batch über Stereomodelle…</translation>
        </message>
        <message>
            <source>Run steps over many stereo models, resumable</source>
            <extracomment>plugin/app/main_window.py:165; plugin/qgis/batch_actions.py:129</extracomment>
            <translation>Schritte über viele Stereomodelle ausführen, fortsetzbar</translation>
        </message>
        <message>
            <source>DEM quality…</source>
            <extracomment>plugin/app/main_window.py:168; plugin/qgis/plugin.py:125</extracomment>
            <translation>DHM-Qualität…</translation>
        </message>
        <message>
            <source>Statistics, histogram, profiles, identify and blunders of a DEM against a reference</source>
            <extracomment>plugin/app/main_window.py:169</extracomment>
            <translation>Statistik, Histogramm, Profile, Abfrage und grobe Fehler eines DHM gegenüber einer Referenz</translation>
        </message>
        <message>
            <source>&amp;Help</source>
            <extracomment>plugin/app/main_window.py:172</extracomment>
            <translation>&amp;Hilfe</translation>
        </message>
        <message>
            <source>&amp;About PhotoDEM</source>
            <extracomment>plugin/app/main_window.py:173</extracomment>
            <translation>&amp;Über PhotoDEM</translation>
        </message>
        <message>
            <source>{0} finished.</source>
            <extracomment>plugin/app/main_window.py:276</extracomment>
            <translation>{0} ist fertig.</translation>
        </message>
        <message>
            <source>{0} failed.</source>
            <extracomment>plugin/app/main_window.py:276</extracomment>
            <translation>{0} ist fehlgeschlagen.</translation>
        </message>
        <message>
            <source>{0} was cancelled.</source>
            <extracomment>plugin/app/main_window.py:277; plugin/qgis/background.py:173</extracomment>
            <translation>{0} wurde abgebrochen.</translation>
        </message>
        <message>
            <source>About PhotoDEM</source>
            <extracomment>plugin/app/main_window.py:412</extracomment>
            <translation>Über PhotoDEM</translation>
        </message>
        <message>
            <source>PhotoDEM: aerial photogrammetry — DSMs by image matching, DTMs by filtering, orthophoto mosaics and automatic georeferencing.</source>
            <extracomment>plugin/app/main_window.py:413</extracomment>
            <translation>PhotoDEM: Luftbildphotogrammetrie — Oberflächenmodelle durch Bildzuordnung, Geländemodelle durch Filterung, Orthophotomosaike und automatische Georeferenzierung.</translation>
        </message>
        <message>
            <source>Other</source>
            <extracomment>plugin/app/main_window.py:183</extracomment>
            <translation>Sonstiges</translation>
        </message>
        <message>
            <source>PhotoDEM</source>
            <extracomment>plugin/app/main_window.py:281; plugin/app/main_window.py:305; plugin/app/map_window.py:171; plugin/widgets/batch_dialog.py:757; plugin/widgets/georef_review.py:436; plugin/widgets/georef_review.py:619; plugin/widgets/georef_review.py:624; plugin/widgets/map_edit_tools.py:358</extracomment>
            <translation>PhotoDEM</translation>
        </message>
        <message>
            <source>Batch running – show</source>
            <extracomment>plugin/app/main_window.py:334</extracomment>
            <translation>Batch läuft – anzeigen</translation>
        </message>
        <message>
            <source>Running {0} …</source>
            <extracomment>plugin/app/main_window.py:268; plugin/widgets/run_panel.py:130</extracomment>
            <translation>{0} läuft …</translation>
        </message>
        <message>
            <source>Tools → Review georeferencing checks and edits its control points.</source>
            <extracomment>plugin/app/main_window.py:287</extracomment>
            <translation>Werkzeuge → Georeferenzierung prüfen zeigt und bearbeitet die Passpunkte.</translation>
        </message>
        <message>
            <source>Batch {0}: summary in {1}</source>
            <extracomment>plugin/app/main_window.py:345</extracomment>
            <translation>Batch {0}: Zusammenfassung in {1}</translation>
        </message>
        <message>
            <source>Difference</source>
            <extracomment>plugin/app/map_window.py:456; plugin/qgis/workspace.py:426</extracomment>
            <translation>Differenz</translation>
        </message>
        <message>
            <source>Ortho</source>
            <extracomment>plugin/app/map_window.py:457; plugin/qgis/workspace.py:427</extracomment>
            <translation>Ortho</translation>
        </message>
        <message>
            <source>Layers</source>
            <extracomment>plugin/app/map_window.py:60</extracomment>
            <translation>Layer</translation>
        </message>
        <message>
            <source>Coordinates of the cursor</source>
            <extracomment>plugin/app/map_window.py:67</extracomment>
            <translation>Koordinaten des Mauszeigers</translation>
        </message>
        <message>
            <source>Value of the top raster under the cursor</source>
            <extracomment>plugin/app/map_window.py:68</extracomment>
            <translation>Wert des obersten Rasters unter dem Mauszeiger</translation>
        </message>
        <message>
            <source>Scale at 96 dpi</source>
            <extracomment>plugin/app/map_window.py:70</extracomment>
            <translation>Maßstab bei 96 dpi</translation>
        </message>
        <message>
            <source>Coordinate reference system of the map</source>
            <extracomment>plugin/app/map_window.py:71</extracomment>
            <translation>Koordinatenbezugssystem der Karte</translation>
        </message>
        <message>
            <source>&amp;Open project…</source>
            <extracomment>plugin/app/map_window.py:89</extracomment>
            <translation>Projekt ö&amp;ffnen…</translation>
        </message>
        <message>
            <source>Add &amp;raster…</source>
            <extracomment>plugin/app/map_window.py:92</extracomment>
            <translation>&amp;Raster hinzufügen…</translation>
        </message>
        <message>
            <source>Add &amp;vector…</source>
            <extracomment>plugin/app/map_window.py:94</extracomment>
            <translation>&amp;Vektor hinzufügen…</translation>
        </message>
        <message>
            <source>Zoom &amp;full</source>
            <extracomment>plugin/app/map_window.py:98</extracomment>
            <translation>&amp;Gesamtansicht</translation>
        </message>
        <message>
            <source>Zoom to &amp;layer</source>
            <extracomment>plugin/app/map_window.py:101</extracomment>
            <translation>Auf &amp;Layer zoomen</translation>
        </message>
        <message>
            <source>Zoom &amp;in</source>
            <extracomment>plugin/app/map_window.py:103</extracomment>
            <translation>Hine&amp;inzoomen</translation>
        </message>
        <message>
            <source>Zoom &amp;out</source>
            <extracomment>plugin/app/map_window.py:106</extracomment>
            <translation>Hera&amp;uszoomen</translation>
        </message>
        <message>
            <source>Map</source>
            <extracomment>plugin/app/map_window.py:116</extracomment>
            <translation>Karte</translation>
        </message>
        <message>
            <source>Open PhotoDEM project</source>
            <extracomment>plugin/app/map_window.py:324; plugin/qgis/project_menu.py:133</extracomment>
            <translation>PhotoDEM-Projekt öffnen</translation>
        </message>
        <message>
            <source>pixels</source>
            <extracomment>plugin/app/map_window.py:163</extracomment>
            <translation>Pixel</translation>
        </message>
        <message>
            <source>no CRS</source>
            <extracomment>plugin/app/map_window.py:164</extracomment>
            <translation>kein KBS</translation>
        </message>
        <message>
            <source>Add raster</source>
            <extracomment>plugin/app/map_window.py:334</extracomment>
            <translation>Raster hinzufügen</translation>
        </message>
        <message>
            <source>Add vector</source>
            <extracomment>plugin/app/map_window.py:334</extracomment>
            <translation>Vektor hinzufügen</translation>
        </message>
        <message>
            <source>Image footprints</source>
            <extracomment>plugin/app/map_window.py:436; plugin/qgis/workspace.py:254</extracomment>
            <translation>Bildfußabdrücke</translation>
        </message>
        <message>
            <source>All files</source>
            <extracomment>plugin/app/map_window.py:335</extracomment>
            <translation>Alle Dateien</translation>
        </message>
        <message>
            <source>PhotoDEM – {0}</source>
            <extracomment>plugin/app/map_window.py:392</extracomment>
            <translation>PhotoDEM – {0}</translation>
        </message>
        <message>
            <source>pixel {0:.1f}, {1:.1f}</source>
            <extracomment>plugin/app/map_window.py:135</extracomment>
            <translation>Pixel {0:.1f}, {1:.1f}</translation>
        </message>
        <message>
            <source>'{0}' has no coordinate reference system: it is shown in pixel coordinates.</source>
            <extracomment>plugin/app/map_window.py:195</extracomment>
            <translation>„{0}“ hat kein Koordinatenbezugssystem: es wird in Pixelkoordinaten angezeigt.</translation>
        </message>
        <message>
            <source>{0} has no overviews and draws slowly: right-click it in the layer list → Build overviews.</source>
            <extracomment>plugin/app/map_window.py:204</extracomment>
            <translation>{0} hat keine Übersichten und wird langsam gezeichnet: Rechtsklick in der Layerliste → Übersichten erzeugen.</translation>
        </message>
        <message>
            <source>'{0}' has no coordinate reference system: it is shown alone, in pixel coordinates.</source>
            <extracomment>plugin/app/map_window.py:224</extracomment>
            <translation>„{0}“ hat kein Koordinatenbezugssystem: es wird allein angezeigt, in Pixelkoordinaten.</translation>
        </message>
        <message>
            <source>Not added to the map (no coordinate reference system): {0}. Show on map in the run panel shows one alone.</source>
            <extracomment>plugin/app/map_window.py:293</extracomment>
            <translation>Nicht zur Karte hinzugefügt (kein Koordinatenbezugssystem): {0}. „Auf Karte zeigen“ im Ausführungsbereich zeigt eine davon allein.</translation>
        </message>
        <message>
            <source>Rasters</source>
            <extracomment>plugin/app/map_window.py:330</extracomment>
            <translation>Raster</translation>
        </message>
        <message>
            <source>Vectors</source>
            <extracomment>plugin/app/map_window.py:332</extracomment>
            <translation>Vektoren</translation>
        </message>
        <message>
            <source>Project {0} opened.</source>
            <extracomment>plugin/app/map_window.py:396; plugin/qgis/project_menu.py:152</extracomment>
            <translation>Projekt {0} geöffnet.</translation>
        </message>
        <message>
            <source>Cannot show '{0}': {1}</source>
            <extracomment>plugin/app/map_window.py:189; plugin/app/map_window.py:236</extracomment>
            <translation>„{0}“ kann nicht angezeigt werden: {1}</translation>
        </message>
        <message>
            <source>Product not shown: {0}</source>
            <extracomment>plugin/app/map_window.py:421</extracomment>
            <translation>Produkt nicht angezeigt: {0}</translation>
        </message>
        <message>
            <source>Footprints and stereo models not shown: {0}</source>
            <extracomment>plugin/app/map_window.py:433</extracomment>
            <translation>Bildfußabdrücke und Stereomodelle nicht angezeigt: {0}</translation>
        </message>
        <message>
            <source>Match this model…</source>
            <extracomment>plugin/app/model_menu.py:106; plugin/qgis/model_actions.py:127</extracomment>
            <translation>Dieses Modell zuordnen…</translation>
        </message>
        <message>
            <source>Filter its DSM…</source>
            <extracomment>plugin/app/model_menu.py:108; plugin/qgis/model_actions.py:129</extracomment>
            <translation>Sein DOM filtern…</translation>
        </message>
        <message>
            <source>A run is going on; wait until it has finished.</source>
            <extracomment>plugin/app/model_menu.py:169</extracomment>
            <translation>Ein Lauf ist im Gange; warten Sie, bis er beendet ist.</translation>
        </message>
        <message>
            <source>Stereo model {0}</source>
            <extracomment>plugin/app/model_menu.py:130; plugin/qgis/model_actions.py:284</extracomment>
            <translation>Stereomodell {0}</translation>
        </message>
        <message>
            <source>Stereo model {0} has no DSM yet ({1}); match it first.</source>
            <extracomment>plugin/app/model_menu.py:185; plugin/qgis/model_actions.py:165</extracomment>
            <translation>Stereomodell {0} hat noch kein DOM ({1}); ordnen Sie es zuerst zu.</translation>
        </message>
        <message>
            <source>PhotoDEM {1}: {0}</source>
            <extracomment>plugin/qgis/background.py:106</extracomment>
            <translation>PhotoDEM {1}: {0}</translation>
        </message>
        <message>
            <source>PhotoDEM: {0}</source>
            <extracomment>plugin/qgis/background.py:106</extracomment>
            <translation>PhotoDEM: {0}</translation>
        </message>
        <message>
            <source>{0} failed; see the log messages.</source>
            <extracomment>plugin/qgis/background.py:175</extracomment>
            <translation>{0} ist fehlgeschlagen; siehe Protokollmeldungen.</translation>
        </message>
        <message>
            <source>The batch was cancelled before it started.</source>
            <extracomment>plugin/qgis/batch_actions.py:60</extracomment>
            <translation>Der Batch wurde abgebrochen, bevor er begann.</translation>
        </message>
        <message>
            <source>Batch {0}: {1}; summary in {2}</source>
            <extracomment>plugin/qgis/batch_actions.py:116; plugin/widgets/batch_dialog.py:647</extracomment>
            <translation>Batch {0}: {1}; Zusammenfassung in {2}</translation>
        </message>
        <message>
            <source>PhotoDEM batch: {0}</source>
            <extracomment>plugin/qgis/batch_actions.py:41</extracomment>
            <translation>PhotoDEM-Batch: {0}</translation>
        </message>
        <message>
            <source>The edits file {0} is locked or unreadable ({1}); close the program that holds it and try again.</source>
            <extracomment>plugin/qgis/edit_maptools.py:74</extracomment>
            <translation>Die Bearbeitungsdatei {0} ist gesperrt oder nicht lesbar ({1}); schließen Sie das Programm, das sie geöffnet hält, und versuchen Sie es erneut.</translation>
        </message>
        <message>
            <source>Re-drape</source>
            <extracomment>plugin/qgis/edit_maptools.py:329; plugin/qgis/editing_toolbar.py:145; plugin/widgets/map_edit_tools.py:417; plugin/widgets/map_vertex_tools.py:466</extracomment>
            <translation>Neu abgreifen</translation>
        </message>
        <message>
            <source>The edits file {0} does not exist.</source>
            <extracomment>plugin/qgis/edit_maptools.py:71</extracomment>
            <translation>Die Bearbeitungsdatei {0} existiert nicht.</translation>
        </message>
        <message>
            <source>The edits file {0} is read-only; make it writable to edit.</source>
            <extracomment>plugin/qgis/edit_maptools.py:73</extracomment>
            <translation>Die Bearbeitungsdatei {0} ist schreibgeschützt; machen Sie sie beschreibbar, um zu bearbeiten.</translation>
        </message>
        <message>
            <source>Open a PhotoDEM project first (PhotoDEM → Open project…).</source>
            <extracomment>plugin/qgis/edit_maptools.py:147; plugin/qgis/editing_toolbar.py:229</extracomment>
            <translation>Öffnen Sie zuerst ein PhotoDEM-Projekt (PhotoDEM → Projekt öffnen…).</translation>
        </message>
        <message>
            <source>Select breaklines or points in an edit layer of the project (breaklines, start, ground or check points) to re-drape them.</source>
            <extracomment>plugin/qgis/edit_maptools.py:316</extracomment>
            <translation>Wählen Sie Bruchkanten oder Punkte in einem Bearbeitungslayer des Projekts (Bruchkanten, Start-, Boden- oder Kontrollpunkte), um ihre Höhen neu abzugreifen.</translation>
        </message>
        <message>
            <source>Choose a surface (DSM or DTM) in the editing toolbar.</source>
            <extracomment>plugin/qgis/edit_maptools.py:198; plugin/widgets/map_edit_tools.py:103</extracomment>
            <translation>Wählen Sie in der Bearbeitungswerkzeugleiste eine Oberfläche (DOM oder DGM).</translation>
        </message>
        <message>
            <source>{0} features re-draped on the surface.</source>
            <extracomment>plugin/qgis/edit_maptools.py:337; plugin/widgets/map_edit_tools.py:516</extracomment>
            <translation>Höhen von {0} Objekten auf der Oberfläche neu abgegriffen.</translation>
        </message>
        <message>
            <source>The layer '{0}' of edits.gpkg is not loaded or missing; add it to the project's edits first.</source>
            <extracomment>plugin/qgis/edit_maptools.py:151</extracomment>
            <translation>Der Layer '{0}' von edits.gpkg ist nicht geladen oder fehlt; fügen Sie ihn zuerst den Bearbeitungen des Projekts hinzu.</translation>
        </message>
        <message>
            <source>The surface '{0}' has no CRS; assign it its CRS (Layer Properties → Source) first.</source>
            <extracomment>plugin/qgis/edit_maptools.py:201</extracomment>
            <translation>Die Oberfläche '{0}' hat kein KBS; weisen Sie ihr zuerst ihr KBS zu (Layereigenschaften → Quelle).</translation>
        </message>
        <message>
            <source>The surface '{0}' is not a file ({1}).</source>
            <extracomment>plugin/qgis/edit_maptools.py:206</extracomment>
            <translation>Die Oberfläche '{0}' ist keine Datei ({1}).</translation>
        </message>
        <message>
            <source>QGIS refused the new feature of '{0}'.</source>
            <extracomment>plugin/qgis/edit_maptools.py:245; plugin/qgis/qc_dock.py:455</extracomment>
            <translation>QGIS hat das neue Objekt von '{0}' abgelehnt.</translation>
        </message>
        <message>
            <source>Nothing selected in '{0}'.</source>
            <extracomment>plugin/qgis/edit_maptools.py:321</extracomment>
            <translation>Nichts ausgewählt in '{0}'.</translation>
        </message>
        <message>
            <source>QGIS cannot edit the layer '{0}'.</source>
            <extracomment>plugin/qgis/edit_maptools.py:160</extracomment>
            <translation>QGIS kann den Layer '{0}' nicht bearbeiten.</translation>
        </message>
        <message>
            <source>Feature {0}: {1}</source>
            <extracomment>plugin/qgis/edit_maptools.py:356</extracomment>
            <translation>Objekt {0}: {1}</translation>
        </message>
        <message>
            <source>Start point</source>
            <extracomment>plugin/qgis/editing_toolbar.py:41; plugin/widgets/edit_flow.py:40; plugin/widgets/map_edit_tools.py:50</extracomment>
            <translation>Startpunkt</translation>
        </message>
        <message>
            <source>Exclusion area</source>
            <extracomment>plugin/qgis/editing_toolbar.py:41; plugin/widgets/edit_flow.py:100; plugin/widgets/edit_forms.py:106; plugin/widgets/map_edit_tools.py:50</extracomment>
            <translation>Ausschlussfläche</translation>
        </message>
        <message>
            <source>Breakline (3-D)</source>
            <extracomment>plugin/qgis/editing_toolbar.py:42</extracomment>
            <translation>Bruchkante (3D)</translation>
        </message>
        <message>
            <source>Ground point (3-D)</source>
            <extracomment>plugin/qgis/editing_toolbar.py:42</extracomment>
            <translation>Bodenpunkt (3D)</translation>
        </message>
        <message>
            <source>Check point (3-D)</source>
            <extracomment>plugin/qgis/editing_toolbar.py:43</extracomment>
            <translation>Kontrollpunkt (3D)</translation>
        </message>
        <message>
            <source>Boundary</source>
            <extracomment>plugin/qgis/editing_toolbar.py:43; plugin/widgets/edit_flow.py:102; plugin/widgets/edit_flow.py:103; plugin/widgets/map_edit_tools.py:52</extracomment>
            <translation>Begrenzung</translation>
        </message>
        <message>
            <source>Seamline</source>
            <extracomment>plugin/qgis/editing_toolbar.py:44; plugin/widgets/edit_flow.py:123; plugin/widgets/map_edit_tools.py:53</extracomment>
            <translation>Schnittlinie</translation>
        </message>
        <message>
            <source>Breakline</source>
            <extracomment>plugin/qgis/editing_toolbar.py:49; plugin/widgets/edit_flow.py:134; plugin/widgets/map_edit_tools.py:51</extracomment>
            <translation>Bruchkante</translation>
        </message>
        <message>
            <source>Ground point</source>
            <extracomment>plugin/qgis/editing_toolbar.py:49; plugin/widgets/edit_flow.py:40; plugin/widgets/map_edit_tools.py:51</extracomment>
            <translation>Bodenpunkt</translation>
        </message>
        <message>
            <source>Check point</source>
            <extracomment>plugin/qgis/editing_toolbar.py:50; plugin/widgets/edit_flow.py:41; plugin/widgets/map_edit_tools.py:52</extracomment>
            <translation>Kontrollpunkt</translation>
        </message>
        <message>
            <source>Z: drape</source>
            <extracomment>plugin/qgis/editing_toolbar.py:55</extracomment>
            <translation>Z: von Oberfläche</translation>
        </message>
        <message>
            <source>Each vertex gets the height of the surface</source>
            <extracomment>plugin/qgis/editing_toolbar.py:55</extracomment>
            <translation>Jeder Stützpunkt erhält die Höhe der Oberfläche</translation>
        </message>
        <message>
            <source>Z: typed</source>
            <extracomment>plugin/qgis/editing_toolbar.py:56</extracomment>
            <translation>Z: eingegeben</translation>
        </message>
        <message>
            <source>Type the height of each vertex</source>
            <extracomment>plugin/qgis/editing_toolbar.py:56</extracomment>
            <translation>Geben Sie die Höhe jedes Stützpunkts ein</translation>
        </message>
        <message>
            <source>Z: interpolate</source>
            <extracomment>plugin/qgis/editing_toolbar.py:57</extracomment>
            <translation>Z: interpoliert</translation>
        </message>
        <message>
            <source>Type the heights of the two ends; the vertices between are interpolated along the line</source>
            <extracomment>plugin/qgis/editing_toolbar.py:58</extracomment>
            <translation>Geben Sie die Höhen der beiden Enden ein; die Stützpunkte dazwischen werden entlang der Linie interpoliert</translation>
        </message>
        <message>
            <source>PhotoDEM editing</source>
            <extracomment>plugin/qgis/editing_toolbar.py:89; plugin/widgets/map_edit_tools.py:382</extracomment>
            <translation>PhotoDEM-Bearbeitung</translation>
        </message>
        <message>
            <source>The DSM or DTM the heights are taken from</source>
            <extracomment>plugin/qgis/editing_toolbar.py:133</extracomment>
            <translation>Das DOM oder DGM, aus dem die Höhen entnommen werden</translation>
        </message>
        <message>
            <source>How the breakline tool gives its vertices their heights</source>
            <extracomment>plugin/qgis/editing_toolbar.py:141</extracomment>
            <translation>Wie das Bruchkantenwerkzeug die Höhen seiner Stützpunkte bestimmt</translation>
        </message>
        <message>
            <source>Re-sample the heights of the selected breaklines and points on the surface</source>
            <extracomment>plugin/qgis/editing_toolbar.py:147</extracomment>
            <translation>Die Höhen der gewählten Bruchkanten und Punkte neu von der Oberfläche abgreifen</translation>
        </message>
        <message>
            <source>Validate</source>
            <extracomment>plugin/qgis/editing_toolbar.py:152</extracomment>
            <translation>Prüfen</translation>
        </message>
        <message>
            <source>Check the current edits, unsaved ones included</source>
            <extracomment>plugin/qgis/editing_toolbar.py:154</extracomment>
            <translation>Die aktuellen Bearbeitungen prüfen, auch die nicht gespeicherten</translation>
        </message>
        <message>
            <source>Surface</source>
            <extracomment>plugin/qgis/editing_toolbar.py:127; plugin/widgets/qc_panel.py:632</extracomment>
            <translation>Oberfläche</translation>
        </message>
        <message>
            <source>Validation: {0} problems.</source>
            <extracomment>plugin/qgis/editing_toolbar.py:238</extracomment>
            <translation>Prüfung: {0} Probleme.</translation>
        </message>
        <message>
            <source>Stereo model:</source>
            <extracomment>plugin/qgis/model_actions.py:259</extracomment>
            <translation>Stereomodell:</translation>
        </message>
        <message>
            <source>Select the stereo-models layer of a PhotoDEM project first.</source>
            <extracomment>plugin/qgis/model_actions.py:242</extracomment>
            <translation>Wählen Sie zuerst den Stereomodell-Layer eines PhotoDEM-Projekts.</translation>
        </message>
        <message>
            <source>The layer '{0}' names no PhotoDEM project.</source>
            <extracomment>plugin/qgis/model_actions.py:100</extracomment>
            <translation>Der Layer „{0}“ nennt kein PhotoDEM-Projekt.</translation>
        </message>
        <message>
            <source>Epipolar pair of {0} written to {1}.</source>
            <extracomment>plugin/qgis/model_actions.py:148</extracomment>
            <translation>Epipolarbildpaar von {0} nach {1} geschrieben.</translation>
        </message>
        <message>
            <source>Stereo model name</source>
            <extracomment>plugin/qgis/model_widget.py:113</extracomment>
            <translation>Name des Stereomodells</translation>
        </message>
        <message>
            <source>Not a PhotoDEM project: no project.toml in this folder.</source>
            <extracomment>plugin/qgis/model_widget.py:63</extracomment>
            <translation>Kein PhotoDEM-Projekt: keine project.toml in diesem Ordner.</translation>
        </message>
        <message>
            <source>Stereo models of the project</source>
            <extracomment>plugin/qgis/model_widget.py:196</extracomment>
            <translation>Stereomodelle des Projekts</translation>
        </message>
        <message>
            <source>The project cannot be read: {0}</source>
            <extracomment>plugin/qgis/model_widget.py:68; plugin/widgets/batch_dialog.py:344</extracomment>
            <translation>Das Projekt ist nicht lesbar: {0}</translation>
        </message>
        <message>
            <source>PhotoDEM needs Python packages that QGIS cannot find: {0}. Debian/Ubuntu: sudo apt install {1}; Windows: install them with the OSGeo4W installer.</source>
            <extracomment>plugin/qgis/plugin.py:47</extracomment>
            <translation>PhotoDEM benötigt Python-Pakete, die QGIS nicht findet: {0}. Debian/Ubuntu: sudo apt install {1}; Windows: mit dem OSGeo4W-Installer installieren.</translation>
        </message>
        <message>
            <source>PhotoDEM algorithms</source>
            <extracomment>plugin/qgis/plugin.py:100</extracomment>
            <translation>PhotoDEM-Algorithmen</translation>
        </message>
        <message>
            <source>Show the PhotoDEM algorithms in the Processing Toolbox</source>
            <extracomment>plugin/qgis/plugin.py:102</extracomment>
            <translation>Die PhotoDEM-Algorithmen im Verarbeitungswerkzeugkasten zeigen</translation>
        </message>
        <message>
            <source>Statistics of an area, histogram, profiles, identify and blunders of a DEM against a reference</source>
            <extracomment>plugin/qgis/plugin.py:127</extracomment>
            <translation>Statistik eines Gebiets, Histogramm, Profile, Abfrage und grobe Fehler eines DHM gegenüber einer Referenz</translation>
        </message>
        <message>
            <source>Open project…</source>
            <extracomment>plugin/qgis/project_menu.py:77</extracomment>
            <translation>Projekt öffnen…</translation>
        </message>
        <message>
            <source>Show a PhotoDEM project on the map: edits, block and products</source>
            <extracomment>plugin/qgis/project_menu.py:79</extracomment>
            <translation>Ein PhotoDEM-Projekt in der Karte zeigen: Bearbeitungen, Block und Produkte</translation>
        </message>
        <message>
            <source>Recent projects</source>
            <extracomment>plugin/qgis/project_menu.py:82</extracomment>
            <translation>Zuletzt geöffnete Projekte</translation>
        </message>
        <message>
            <source>PhotoDEM project</source>
            <extracomment>plugin/qgis/project_menu.py:134</extracomment>
            <translation>PhotoDEM-Projekt</translation>
        </message>
        <message>
            <source>The project {0} is no longer there; it was removed from the recent projects.</source>
            <extracomment>plugin/qgis/project_menu.py:124</extracomment>
            <translation>Das Projekt {0} ist nicht mehr vorhanden; es wurde aus den zuletzt geöffneten Projekten entfernt.</translation>
        </message>
        <message>
            <source>PhotoDEM aerial photogrammetry</source>
            <extracomment>plugin/qgis/provider.py:34</extracomment>
            <translation>PhotoDEM Luftbildphotogrammetrie</translation>
        </message>
        <message>
            <source>PhotoDEM – DEM quality</source>
            <extracomment>plugin/qgis/qc_dock.py:155</extracomment>
            <translation>PhotoDEM – DHM-Qualität</translation>
        </message>
        <message>
            <source>Reference</source>
            <extracomment>plugin/qgis/qc_dock.py:193; plugin/widgets/qc_panel.py:132</extracomment>
            <translation>Referenz</translation>
        </message>
        <message>
            <source>Classes (optional)</source>
            <extracomment>plugin/qgis/qc_dock.py:194; plugin/widgets/qc_panel.py:134</extracomment>
            <translation>Klassen (optional)</translation>
        </message>
        <message>
            <source>visible extent</source>
            <extracomment>plugin/qgis/qc_dock.py:316</extracomment>
            <translation>sichtbare Ausdehnung</translation>
        </message>
        <message>
            <source>whole model</source>
            <extracomment>plugin/qgis/qc_dock.py:320; plugin/widgets/qc_panel.py:107; plugin/widgets/qc_panel.py:360; plugin/widgets/qc_panel.py:439</extracomment>
            <translation>ganzes Modell</translation>
        </message>
        <message>
            <source>Select a line layer in the layer tree first.</source>
            <extracomment>plugin/qgis/qc_dock.py:335</extracomment>
            <translation>Wählen Sie zuerst einen Linienlayer im Layerbaum.</translation>
        </message>
        <message>
            <source>Choose a DTM of a PhotoDEM filter run (with its mask.tif) in the Filter review tab.</source>
            <extracomment>plugin/qgis/qc_dock.py:394</extracomment>
            <translation>Wählen Sie im Reiter Filterprüfung ein DGM eines PhotoDEM-Filterlaufs (mit mask.tif).</translation>
        </message>
        <message>
            <source>eliminated</source>
            <extracomment>plugin/qgis/qc_dock.py:401</extracomment>
            <translation>eliminiert</translation>
        </message>
        <message>
            <source>Draw area</source>
            <extracomment>plugin/qgis/qc_dock.py:200</extracomment>
            <translation>Gebiet zeichnen</translation>
        </message>
        <message>
            <source>Visible extent</source>
            <extracomment>plugin/qgis/qc_dock.py:201</extracomment>
            <translation>Sichtbare Ausdehnung</translation>
        </message>
        <message>
            <source>Whole model</source>
            <extracomment>plugin/qgis/qc_dock.py:202; plugin/widgets/qc_panel.py:194</extracomment>
            <translation>Ganzes Modell</translation>
        </message>
        <message>
            <source>Show eliminated cells</source>
            <extracomment>plugin/qgis/qc_dock.py:203</extracomment>
            <translation>Eliminierte Zellen zeigen</translation>
        </message>
        <message>
            <source>Draw profile</source>
            <extracomment>plugin/qgis/qc_dock.py:204</extracomment>
            <translation>Profil zeichnen</translation>
        </message>
        <message>
            <source>Profile of feature</source>
            <extracomment>plugin/qgis/qc_dock.py:205</extracomment>
            <translation>Profil eines Objekts</translation>
        </message>
        <message>
            <source>Identify</source>
            <extracomment>plugin/qgis/qc_dock.py:206; plugin/widgets/qc_panel.py:144</extracomment>
            <translation>Abfragen</translation>
        </message>
        <message>
            <source>eliminated cells ({0})</source>
            <extracomment>plugin/qgis/qc_dock.py:397</extracomment>
            <translation>eliminierte Zellen ({0})</translation>
        </message>
        <message>
            <source>Open a PhotoDEM project first: the edit goes into its layer '{0}'.</source>
            <extracomment>plugin/qgis/qc_dock.py:440</extracomment>
            <translation>Öffnen Sie zuerst ein PhotoDEM-Projekt: Die Bearbeitung kommt in dessen Layer „{0}“.</translation>
        </message>
        <message>
            <source>keep</source>
            <extracomment>plugin/qgis/styles.py:50</extracomment>
            <translation>behalten</translation>
        </message>
        <message>
            <source>remove</source>
            <extracomment>plugin/qgis/styles.py:50</extracomment>
            <translation>entfernen</translation>
        </message>
        <message>
            <source>exclude</source>
            <extracomment>plugin/qgis/styles.py:50</extracomment>
            <translation>ausschließen</translation>
        </message>
        <message>
            <source>breakline</source>
            <extracomment>plugin/qgis/styles.py:51; plugin/widgets/edit_forms.py:42; plugin/widgets/qc_plots.py:156</extracomment>
            <translation>Bruchkante</translation>
        </message>
        <message>
            <source>structure line</source>
            <extracomment>plugin/qgis/styles.py:51; plugin/widgets/edit_forms.py:42</extracomment>
            <translation>Strukturlinie</translation>
        </message>
        <message>
            <source>other values</source>
            <extracomment>plugin/qgis/styles.py:52</extracomment>
            <translation>andere Werte</translation>
        </message>
        <message>
            <source>keep, remove or exclude</source>
            <extracomment>plugin/qgis/styles.py:59</extracomment>
            <translation>behalten, entfernen oder ausschließen</translation>
        </message>
        <message>
            <source>breakline or structure_line</source>
            <extracomment>plugin/qgis/styles.py:60</extracomment>
            <translation>Bruchkante (breakline) oder Strukturlinie (structure_line)</translation>
        </message>
        <message>
            <source>height between -500 m and 9000 m</source>
            <extracomment>plugin/qgis/styles.py:61</extracomment>
            <translation>Höhe zwischen -500 m und 9000 m</translation>
        </message>
        <message>
            <source>a non-empty id</source>
            <extracomment>plugin/qgis/styles.py:62</extracomment>
            <translation>eine nicht leere Kennung</translation>
        </message>
        <message>
            <source>PhotoDEM validation</source>
            <extracomment>plugin/qgis/validation_dock.py:107</extracomment>
            <translation>PhotoDEM-Prüfung</translation>
        </message>
        <message>
            <source>error</source>
            <extracomment>plugin/qgis/validation_dock.py:132</extracomment>
            <translation>Fehler</translation>
        </message>
        <message>
            <source>warning</source>
            <extracomment>plugin/qgis/validation_dock.py:132</extracomment>
            <translation>Warnung</translation>
        </message>
        <message>
            <source>Problem</source>
            <extracomment>plugin/qgis/validation_dock.py:113</extracomment>
            <translation>Problem</translation>
        </message>
        <message>
            <source>Severity</source>
            <extracomment>plugin/qgis/validation_dock.py:113</extracomment>
            <translation>Schwere</translation>
        </message>
        <message>
            <source>Layer</source>
            <extracomment>plugin/qgis/validation_dock.py:113</extracomment>
            <translation>Layer</translation>
        </message>
        <message>
            <source>Feature</source>
            <extracomment>plugin/qgis/validation_dock.py:114</extracomment>
            <translation>Objekt</translation>
        </message>
        <message>
            <source>unsaved</source>
            <extracomment>plugin/qgis/validation_dock.py:138</extracomment>
            <translation>ungespeichert</translation>
        </message>
        <message>
            <source>No problems found.</source>
            <extracomment>plugin/qgis/validation_dock.py:148</extracomment>
            <translation>Keine Probleme gefunden.</translation>
        </message>
        <message>
            <source>Breakline {0}</source>
            <extracomment>plugin/qgis/validation_dock.py:96</extracomment>
            <translation>Bruchkante {0}</translation>
        </message>
        <message>
            <source>Start points</source>
            <extracomment>plugin/qgis/workspace.py:408; plugin/widgets/edit_session.py:357</extracomment>
            <translation>Startpunkte</translation>
        </message>
        <message>
            <source>Exclusion areas</source>
            <extracomment>plugin/qgis/workspace.py:408; plugin/widgets/edit_session.py:357</extracomment>
            <translation>Ausschlussflächen</translation>
        </message>
        <message>
            <source>Boundaries</source>
            <extracomment>plugin/qgis/workspace.py:409; plugin/widgets/edit_session.py:358</extracomment>
            <translation>Begrenzungen</translation>
        </message>
        <message>
            <source>Breaklines</source>
            <extracomment>plugin/qgis/workspace.py:409; plugin/widgets/edit_session.py:358</extracomment>
            <translation>Bruchkanten</translation>
        </message>
        <message>
            <source>Ground points</source>
            <extracomment>plugin/qgis/workspace.py:410; plugin/widgets/edit_session.py:359</extracomment>
            <translation>Bodenpunkte</translation>
        </message>
        <message>
            <source>Check points</source>
            <extracomment>plugin/qgis/workspace.py:411; plugin/widgets/edit_session.py:360</extracomment>
            <translation>Kontrollpunkte</translation>
        </message>
        <message>
            <source>Edits</source>
            <extracomment>plugin/qgis/workspace.py:142</extracomment>
            <translation>Bearbeitungen</translation>
        </message>
        <message>
            <source>Block</source>
            <extracomment>plugin/qgis/workspace.py:142</extracomment>
            <translation>Block</translation>
        </message>
        <message>
            <source>Products</source>
            <extracomment>plugin/qgis/workspace.py:143; plugin/widgets/batch_dialog.py:246</extracomment>
            <translation>Produkte</translation>
        </message>
        <message>
            <source>The project has no edits.gpkg: start points, exclusion areas and breaklines cannot be drawn.</source>
            <extracomment>plugin/qgis/workspace.py:170</extracomment>
            <translation>Das Projekt hat keine edits.gpkg: Startpunkte, Ausschlussflächen und Bruchkanten können nicht gezeichnet werden.</translation>
        </message>
        <message>
            <source>Create edits.gpkg</source>
            <extracomment>plugin/qgis/workspace.py:171</extracomment>
            <translation>edits.gpkg anlegen</translation>
        </message>
        <message>
            <source>Add them</source>
            <extracomment>plugin/qgis/workspace.py:188; plugin/qgis/workspace.py:223</extracomment>
            <translation>Hinzufügen</translation>
        </message>
        <message>
            <source>{0} cannot be written: the edit layers are loaded read-only.</source>
            <extracomment>plugin/qgis/workspace.py:177</extracomment>
            <translation>{0} ist nicht beschreibbar: die Bearbeitungslayer werden schreibgeschützt geladen.</translation>
        </message>
        <message>
            <source>edits.gpkg lacks the layer(s) {0}.</source>
            <extracomment>plugin/qgis/workspace.py:187; plugin/qgis/workspace.py:222</extracomment>
            <translation>In edits.gpkg fehlen die Layer {0}.</translation>
        </message>
        <message>
            <source>Cannot load the layer {0} of {1}.</source>
            <extracomment>plugin/qgis/workspace.py:196</extracomment>
            <translation>Der Layer {0} von {1} kann nicht geladen werden.</translation>
        </message>
        <message>
            <source>Save or discard the edits of {0} first; edits.gpkg was not changed.</source>
            <extracomment>plugin/qgis/workspace.py:220</extracomment>
            <translation>Speichern oder verwerfen Sie zuerst die Bearbeitungen von {0}; edits.gpkg wurde nicht geändert.</translation>
        </message>
        <message>
            <source>Cannot load {0}.</source>
            <extracomment>plugin/qgis/workspace.py:273</extracomment>
            <translation>{0} kann nicht geladen werden.</translation>
        </message>
        <message>
            <source>hillshade</source>
            <extracomment>plugin/qgis/workspace.py:277; plugin/qgis/workspace.py:326</extracomment>
            <translation>Schummerung</translation>
        </message>
        <message>
            <source>The block layers cannot be made: {0}</source>
            <extracomment>plugin/qgis/workspace.py:252</extracomment>
            <translation>Die Block-Layer können nicht erstellt werden: {0}</translation>
        </message>
        <message>
            <source>Batch over stereo models</source>
            <extracomment>plugin/widgets/batch_dialog.py:104</extracomment>
            <translation>Batch über Stereomodelle</translation>
        </message>
        <message>
            <source>project folder (with project.toml)</source>
            <extracomment>plugin/widgets/batch_dialog.py:138; plugin/widgets/parameter_form.py:151</extracomment>
            <translation>Projektordner (mit project.toml)</translation>
        </message>
        <message>
            <source>Open batch file…</source>
            <extracomment>plugin/widgets/batch_dialog.py:139</extracomment>
            <translation>Batch-Datei öffnen…</translation>
        </message>
        <message>
            <source>Double-click a row to open its log.</source>
            <extracomment>plugin/widgets/batch_dialog.py:153</extracomment>
            <translation>Doppelklick auf eine Zeile öffnet ihr Protokoll.</translation>
        </message>
        <message>
            <source>Steps</source>
            <extracomment>plugin/widgets/batch_dialog.py:167</extracomment>
            <translation>Schritte</translation>
        </message>
        <message>
            <source>Refine in object space</source>
            <extracomment>plugin/widgets/batch_dialog.py:172</extracomment>
            <translation>Im Objektraum verfeinern</translation>
        </message>
        <message>
            <source>DTM filter</source>
            <extracomment>plugin/widgets/batch_dialog.py:173; plugin/widgets/batch_dialog.py:189</extracomment>
            <translation>DGM-Filter</translation>
        </message>
        <message>
            <source>Worker processes (default: cores − 1)</source>
            <extracomment>plugin/widgets/batch_dialog.py:201</extracomment>
            <translation>Worker-Prozesse (Vorgabe: Kerne − 1)</translation>
        </message>
        <message>
            <source>empty = this machine</source>
            <extracomment>plugin/widgets/batch_dialog.py:206</extracomment>
            <translation>leer = dieser Rechner</translation>
        </message>
        <message>
            <source>Address of a Dask scheduler (tcp://host:8786) whose workers run the batch; the project must be on storage every worker sees at the same path.</source>
            <extracomment>plugin/widgets/batch_dialog.py:207</extracomment>
            <translation>Adresse eines Dask-Schedulers (tcp://host:8786), dessen Worker den Batch ausführen; das Projekt muss auf einem Speicher liegen, den jeder Worker unter demselben Pfad sieht.</translation>
        </message>
        <message>
            <source>The log of the batch appears here.</source>
            <extracomment>plugin/widgets/batch_dialog.py:228</extracomment>
            <translation>Hier erscheint das Protokoll des Batches.</translation>
        </message>
        <message>
            <source>Open</source>
            <extracomment>plugin/widgets/batch_dialog.py:231; plugin/widgets/run_panel.py:238</extracomment>
            <translation>Öffnen</translation>
        </message>
        <message>
            <source>Show in folder</source>
            <extracomment>plugin/widgets/batch_dialog.py:232; plugin/widgets/run_panel.py:238</extracomment>
            <translation>Im Ordner zeigen</translation>
        </message>
        <message>
            <source>Log</source>
            <extracomment>plugin/widgets/batch_dialog.py:245; plugin/widgets/run_panel.py:93</extracomment>
            <translation>Protokoll</translation>
        </message>
        <message>
            <source>Run</source>
            <extracomment>plugin/widgets/batch_dialog.py:258; plugin/widgets/run_panel.py:48</extracomment>
            <translation>Ausführen</translation>
        </message>
        <message>
            <source>Write the batch file of these choices and run it</source>
            <extracomment>plugin/widgets/batch_dialog.py:260</extracomment>
            <translation>Die Batch-Datei dieser Auswahl schreiben und ausführen</translation>
        </message>
        <message>
            <source>Resume</source>
            <extracomment>plugin/widgets/batch_dialog.py:261</extracomment>
            <translation>Fortsetzen</translation>
        </message>
        <message>
            <source>Run the batch file again; finished tasks are skipped</source>
            <extracomment>plugin/widgets/batch_dialog.py:262</extracomment>
            <translation>Die Batch-Datei erneut ausführen; fertige Aufgaben werden übersprungen</translation>
        </message>
        <message>
            <source>Re-run failed</source>
            <extracomment>plugin/widgets/batch_dialog.py:263</extracomment>
            <translation>Fehlgeschlagene erneut ausführen</translation>
        </message>
        <message>
            <source>Cancel</source>
            <extracomment>plugin/widgets/batch_dialog.py:264; plugin/widgets/edit_session.py:92; plugin/widgets/georef_review.py:596; plugin/widgets/qc_panel.py:159; plugin/widgets/run_panel.py:51</extracomment>
            <translation>Abbrechen</translation>
        </message>
        <message>
            <source>Close</source>
            <extracomment>plugin/widgets/batch_dialog.py:265; plugin/widgets/georef_review.py:279</extracomment>
            <translation>Schließen</translation>
        </message>
        <message>
            <source>Batch is running</source>
            <extracomment>plugin/widgets/batch_dialog.py:724</extracomment>
            <translation>Batch läuft</translation>
        </message>
        <message>
            <source>The batch is still running. Cancel it, or keep it running in the background?</source>
            <extracomment>plugin/widgets/batch_dialog.py:725</extracomment>
            <translation>Der Batch läuft noch. Abbrechen oder im Hintergrund weiterlaufen lassen?</translation>
        </message>
        <message>
            <source>Cancel the batch</source>
            <extracomment>plugin/widgets/batch_dialog.py:727</extracomment>
            <translation>Batch abbrechen</translation>
        </message>
        <message>
            <source>Keep running</source>
            <extracomment>plugin/widgets/batch_dialog.py:728</extracomment>
            <translation>Weiterlaufen lassen</translation>
        </message>
        <message>
            <source>Back</source>
            <extracomment>plugin/widgets/batch_dialog.py:729</extracomment>
            <translation>Zurück</translation>
        </message>
        <message>
            <source>done</source>
            <extracomment>plugin/widgets/batch_dialog.py:47</extracomment>
            <translation>fertig</translation>
        </message>
        <message>
            <source>failed</source>
            <extracomment>plugin/widgets/batch_dialog.py:47</extracomment>
            <translation>fehlgeschlagen</translation>
        </message>
        <message>
            <source>not run</source>
            <extracomment>plugin/widgets/batch_dialog.py:47</extracomment>
            <translation>nicht gelaufen</translation>
        </message>
        <message>
            <source>skipped</source>
            <extracomment>plugin/widgets/batch_dialog.py:48</extracomment>
            <translation>übersprungen</translation>
        </message>
        <message>
            <source>cancelled</source>
            <extracomment>plugin/widgets/batch_dialog.py:48</extracomment>
            <translation>abgebrochen</translation>
        </message>
        <message>
            <source>running</source>
            <extracomment>plugin/widgets/batch_dialog.py:48</extracomment>
            <translation>läuft</translation>
        </message>
        <message>
            <source>waiting</source>
            <extracomment>plugin/widgets/batch_dialog.py:49</extracomment>
            <translation>wartet</translation>
        </message>
        <message>
            <source>Model</source>
            <extracomment>plugin/widgets/batch_dialog.py:147</extracomment>
            <translation>Modell</translation>
        </message>
        <message>
            <source>Kind</source>
            <extracomment>plugin/widgets/batch_dialog.py:147; plugin/widgets/edit_forms.py:128</extracomment>
            <translation>Art</translation>
        </message>
        <message>
            <source>B/H</source>
            <extracomment>plugin/widgets/batch_dialog.py:147</extracomment>
            <translation>B/H</translation>
        </message>
        <message>
            <source>Overlap</source>
            <extracomment>plugin/widgets/batch_dialog.py:147; plugin/widgets/georef_review.py:54</extracomment>
            <translation>Überlappung</translation>
        </message>
        <message>
            <source>Progress</source>
            <extracomment>plugin/widgets/batch_dialog.py:148</extracomment>
            <translation>Fortschritt</translation>
        </message>
        <message>
            <source>State</source>
            <extracomment>plugin/widgets/batch_dialog.py:148</extracomment>
            <translation>Zustand</translation>
        </message>
        <message>
            <source>Matching method</source>
            <extracomment>plugin/widgets/batch_dialog.py:187</extracomment>
            <translation>Zuordnungsverfahren</translation>
        </message>
        <message>
            <source>Matching preset</source>
            <extracomment>plugin/widgets/batch_dialog.py:188</extracomment>
            <translation>Voreinstellung der Zuordnung</translation>
        </message>
        <message>
            <source>Filter preset</source>
            <extracomment>plugin/widgets/batch_dialog.py:190</extracomment>
            <translation>Voreinstellung des Filters</translation>
        </message>
        <message>
            <source>Single orthophotos or a mosaic</source>
            <extracomment>plugin/widgets/batch_dialog.py:191</extracomment>
            <translation>Einzelne Orthofotos oder ein Mosaik</translation>
        </message>
        <message>
            <source>Workers</source>
            <extracomment>plugin/widgets/batch_dialog.py:202</extracomment>
            <translation>Worker</translation>
        </message>
        <message>
            <source>Scheduler</source>
            <extracomment>plugin/widgets/batch_dialog.py:210</extracomment>
            <translation>Scheduler</translation>
        </message>
        <message>
            <source>Choose a project folder, or open a batch file.</source>
            <extracomment>plugin/widgets/batch_dialog.py:338</extracomment>
            <translation>Wählen Sie einen Projektordner oder öffnen Sie eine Batch-Datei.</translation>
        </message>
        <message>
            <source>Choose a project folder (with project.toml) first.</source>
            <extracomment>plugin/widgets/batch_dialog.py:403</extracomment>
            <translation>Wählen Sie zuerst einen Projektordner (mit project.toml).</translation>
        </message>
        <message>
            <source>Cancelling …</source>
            <extracomment>plugin/widgets/batch_dialog.py:531; plugin/widgets/run_panel.py:154</extracomment>
            <translation>Wird abgebrochen …</translation>
        </message>
        <message>
            <source>No log yet: the task has not started.</source>
            <extracomment>plugin/widgets/batch_dialog.py:705</extracomment>
            <translation>Noch kein Protokoll: die Aufgabe hat noch nicht begonnen.</translation>
        </message>
        <message>
            <source>Run writes the batch file into {0}</source>
            <extracomment>plugin/widgets/batch_dialog.py:350</extracomment>
            <translation>Ausführen schreibt die Batch-Datei nach {0}</translation>
        </message>
        <message>
            <source>Open batch file</source>
            <extracomment>plugin/widgets/batch_dialog.py:420</extracomment>
            <translation>Batch-Datei öffnen</translation>
        </message>
        <message>
            <source>Batch files (*.toml)</source>
            <extracomment>plugin/widgets/batch_dialog.py:420</extracomment>
            <translation>Batch-Dateien (*.toml)</translation>
        </message>
        <message>
            <source>Running batch file {0} …</source>
            <extracomment>plugin/widgets/batch_dialog.py:517</extracomment>
            <translation>Batch-Datei {0} läuft …</translation>
        </message>
        <message>
            <source>elapsed {0} · remaining {1}</source>
            <extracomment>plugin/widgets/batch_dialog.py:633</extracomment>
            <translation>vergangen {0} · verbleibend {1}</translation>
        </message>
        <message>
            <source>Warning: </source>
            <extracomment>plugin/widgets/batch_dialog.py:637; plugin/widgets/run_panel.py:174</extracomment>
            <translation>Warnung: </translation>
        </message>
        <message>
            <source>Error: </source>
            <extracomment>plugin/widgets/batch_dialog.py:637; plugin/widgets/run_panel.py:188</extracomment>
            <translation>Fehler: </translation>
        </message>
        <message>
            <source>Batch file: {0}
Run it again with: photodem batch {0}</source>
            <extracomment>plugin/widgets/batch_dialog.py:453</extracomment>
            <translation>Batch-Datei: {0}
Erneut ausführen mit: photodem batch {0}</translation>
        </message>
        <message>
            <source>The batch file cannot be used: {0}</source>
            <extracomment>plugin/widgets/batch_dialog.py:426</extracomment>
            <translation>Die Batch-Datei kann nicht verwendet werden: {0}</translation>
        </message>
        <message>
            <source>Id</source>
            <extracomment>plugin/widgets/edit_flow.py:78</extracomment>
            <translation>Kennung</translation>
        </message>
        <message>
            <source>Note</source>
            <extracomment>plugin/widgets/edit_flow.py:78; plugin/widgets/edit_forms.py:115; plugin/widgets/edit_forms.py:94</extracomment>
            <translation>Notiz</translation>
        </message>
        <message>
            <source>Type the heights of the two ends; the others are interpolated.</source>
            <extracomment>plugin/widgets/edit_flow.py:152</extracomment>
            <translation>Geben Sie die Höhen der beiden Enden ein; die übrigen werden interpoliert.</translation>
        </message>
        <message>
            <source>No surface chosen; type the height.</source>
            <extracomment>plugin/widgets/edit_flow.py:48</extracomment>
            <translation>Keine Oberfläche gewählt; geben Sie die Höhe ein.</translation>
        </message>
        <message>
            <source>The point lies outside every stereo model; no model will use it.</source>
            <extracomment>plugin/widgets/edit_flow.py:74</extracomment>
            <translation>Der Punkt liegt außerhalb aller Stereomodelle; kein Modell wird ihn verwenden.</translation>
        </message>
        <message>
            <source>Name</source>
            <extracomment>plugin/widgets/edit_flow.py:102</extracomment>
            <translation>Name</translation>
        </message>
        <message>
            <source>Breakline refused, nothing written: {0}</source>
            <extracomment>plugin/widgets/edit_flow.py:127</extracomment>
            <translation>Bruchkante abgelehnt, nichts geschrieben: {0}</translation>
        </message>
        <message>
            <source>Every vertex of a breakline needs a height.</source>
            <extracomment>algorithms/project/edit_rules.py:186; plugin/widgets/edit_flow.py:161</extracomment>
            <translation>Jeder Stützpunkt einer Bruchkante braucht eine Höhe.</translation>
        </message>
        <message>
            <source>Polygon refused, nothing written: {0}</source>
            <extracomment>plugin/widgets/edit_flow.py:95</extracomment>
            <translation>Polygon abgelehnt, nichts geschrieben: {0}</translation>
        </message>
        <message>
            <source>keep (surface stays as measured)</source>
            <extracomment>plugin/widgets/edit_forms.py:34</extracomment>
            <translation>behalten (Oberfläche bleibt wie gemessen)</translation>
        </message>
        <message>
            <source>remove (not matched; bridged in the DTM)</source>
            <extracomment>plugin/widgets/edit_forms.py:35</extracomment>
            <translation>entfernen (nicht zugeordnet; im DGM überbrückt)</translation>
        </message>
        <message>
            <source>exclude (as remove)</source>
            <extracomment>plugin/widgets/edit_forms.py:36</extracomment>
            <translation>ausschließen (wie entfernen)</translation>
        </message>
        <message>
            <source>type a height</source>
            <extracomment>plugin/widgets/edit_forms.py:52</extracomment>
            <translation>Höhe eingeben</translation>
        </message>
        <message>
            <source>Height</source>
            <extracomment>plugin/widgets/edit_forms.py:91</extracomment>
            <translation>Höhe</translation>
        </message>
        <message>
            <source>What should happen inside the area?</source>
            <extracomment>plugin/widgets/edit_forms.py:107</extracomment>
            <translation>Was soll innerhalb der Fläche geschehen?</translation>
        </message>
        <message>
            <source>Action</source>
            <extracomment>plugin/widgets/edit_forms.py:113; plugin/widgets/qc_panel.py:276</extracomment>
            <translation>Aktion</translation>
        </message>
        <message>
            <source>Breakline heights</source>
            <extracomment>plugin/widgets/edit_forms.py:123</extracomment>
            <translation>Höhen der Bruchkante</translation>
        </message>
        <message>
            <source>Invalid polygon</source>
            <extracomment>plugin/widgets/edit_forms.py:192</extracomment>
            <translation>Ungültiges Polygon</translation>
        </message>
        <message>
            <source>Use the repaired polygon?</source>
            <extracomment>plugin/widgets/edit_forms.py:193</extracomment>
            <translation>Das reparierte Polygon verwenden?</translation>
        </message>
        <message>
            <source>Vertex {0}</source>
            <extracomment>plugin/widgets/edit_forms.py:135</extracomment>
            <translation>Stützpunkt {0}</translation>
        </message>
        <message>
            <source>Add start point</source>
            <extracomment>plugin/widgets/edit_session.py:37</extracomment>
            <translation>Startpunkt hinzufügen</translation>
        </message>
        <message>
            <source>Add exclusion area</source>
            <extracomment>plugin/widgets/edit_session.py:37</extracomment>
            <translation>Ausschlussfläche hinzufügen</translation>
        </message>
        <message>
            <source>Add boundary</source>
            <extracomment>plugin/widgets/edit_session.py:38</extracomment>
            <translation>Begrenzung hinzufügen</translation>
        </message>
        <message>
            <source>Add breakline</source>
            <extracomment>plugin/widgets/edit_session.py:38</extracomment>
            <translation>Bruchkante hinzufügen</translation>
        </message>
        <message>
            <source>Add ground point</source>
            <extracomment>plugin/widgets/edit_session.py:39</extracomment>
            <translation>Bodenpunkt hinzufügen</translation>
        </message>
        <message>
            <source>Add seamline</source>
            <extracomment>plugin/widgets/edit_session.py:39</extracomment>
            <translation>Schnittlinie hinzufügen</translation>
        </message>
        <message>
            <source>Add check point</source>
            <extracomment>plugin/widgets/edit_session.py:40</extracomment>
            <translation>Kontrollpunkt hinzufügen</translation>
        </message>
        <message>
            <source>Add feature</source>
            <extracomment>plugin/widgets/edit_session.py:41</extracomment>
            <translation>Objekt hinzufügen</translation>
        </message>
        <message>
            <source>Change start point</source>
            <extracomment>plugin/widgets/edit_session.py:46</extracomment>
            <translation>Startpunkt ändern</translation>
        </message>
        <message>
            <source>Change exclusion area</source>
            <extracomment>plugin/widgets/edit_session.py:47</extracomment>
            <translation>Ausschlussfläche ändern</translation>
        </message>
        <message>
            <source>Change boundary</source>
            <extracomment>plugin/widgets/edit_session.py:48</extracomment>
            <translation>Begrenzung ändern</translation>
        </message>
        <message>
            <source>Change breakline</source>
            <extracomment>plugin/widgets/edit_session.py:48</extracomment>
            <translation>Bruchkante ändern</translation>
        </message>
        <message>
            <source>Change ground point</source>
            <extracomment>plugin/widgets/edit_session.py:49</extracomment>
            <translation>Bodenpunkt ändern</translation>
        </message>
        <message>
            <source>Change seamline</source>
            <extracomment>plugin/widgets/edit_session.py:49</extracomment>
            <translation>Schnittlinie ändern</translation>
        </message>
        <message>
            <source>Change check point</source>
            <extracomment>plugin/widgets/edit_session.py:50</extracomment>
            <translation>Kontrollpunkt ändern</translation>
        </message>
        <message>
            <source>Change feature</source>
            <extracomment>plugin/widgets/edit_session.py:51</extracomment>
            <translation>Objekt ändern</translation>
        </message>
        <message>
            <source>Delete start point</source>
            <extracomment>plugin/widgets/edit_session.py:56</extracomment>
            <translation>Startpunkt löschen</translation>
        </message>
        <message>
            <source>Delete exclusion area</source>
            <extracomment>plugin/widgets/edit_session.py:57</extracomment>
            <translation>Ausschlussfläche löschen</translation>
        </message>
        <message>
            <source>Delete boundary</source>
            <extracomment>plugin/widgets/edit_session.py:58</extracomment>
            <translation>Begrenzung löschen</translation>
        </message>
        <message>
            <source>Delete breakline</source>
            <extracomment>plugin/widgets/edit_session.py:58</extracomment>
            <translation>Bruchkante löschen</translation>
        </message>
        <message>
            <source>Delete ground point</source>
            <extracomment>plugin/widgets/edit_session.py:59</extracomment>
            <translation>Bodenpunkt löschen</translation>
        </message>
        <message>
            <source>Delete seamline</source>
            <extracomment>plugin/widgets/edit_session.py:59</extracomment>
            <translation>Schnittlinie löschen</translation>
        </message>
        <message>
            <source>Delete check point</source>
            <extracomment>plugin/widgets/edit_session.py:60</extracomment>
            <translation>Kontrollpunkt löschen</translation>
        </message>
        <message>
            <source>Delete feature</source>
            <extracomment>plugin/widgets/edit_session.py:61; plugin/widgets/map_edit_tools.py:415</extracomment>
            <translation>Objekt löschen</translation>
        </message>
        <message>
            <source>Unsaved edits</source>
            <extracomment>plugin/widgets/edit_session.py:84</extracomment>
            <translation>Ungespeicherte Bearbeitungen</translation>
        </message>
        <message>
            <source>Save</source>
            <extracomment>plugin/widgets/edit_session.py:90; plugin/widgets/georef_review.py:275</extracomment>
            <translation>Speichern</translation>
        </message>
        <message>
            <source>Discard</source>
            <extracomment>plugin/widgets/edit_session.py:91</extracomment>
            <translation>Verwerfen</translation>
        </message>
        <message>
            <source>The edits of this project are not saved. Save them to {0}?</source>
            <extracomment>plugin/widgets/edit_session.py:85</extracomment>
            <translation>Die Bearbeitungen dieses Projekts sind nicht gespeichert. In {0} speichern?</translation>
        </message>
        <message>
            <source>Edits not saved</source>
            <extracomment>plugin/widgets/edit_session.py:350</extracomment>
            <translation>Bearbeitungen nicht gespeichert</translation>
        </message>
        <message>
            <source>Layer '{0}' has no field(s) {1}.</source>
            <extracomment>plugin/widgets/edit_session.py:254</extracomment>
            <translation>Der Layer '{0}' hat kein(e) Feld(er) {1}.</translation>
        </message>
        <message>
            <source>Layer '{0}' has no feature {1}.</source>
            <extracomment>plugin/widgets/edit_session.py:287</extracomment>
            <translation>Der Layer '{0}' hat kein Objekt {1}.</translation>
        </message>
        <message>
            <source>The edits file {0} was changed by another program (QGIS?) since it was opened here; saving would lose those changes. Nothing was written. Open the project again to see them.</source>
            <extracomment>plugin/widgets/edit_session.py:317</extracomment>
            <translation>Die Bearbeitungsdatei {0} wurde seit dem Öffnen hier von einem anderen Programm (QGIS?) geändert; Speichern würde diese Änderungen verlieren. Es wurde nichts geschrieben. Öffnen Sie das Projekt erneut, um sie zu sehen.</translation>
        </message>
        <message>
            <source>The edits file {0} cannot be saved now ({1}); nothing was written. Close the program that holds it and save again.</source>
            <extracomment>plugin/widgets/edit_session.py:323</extracomment>
            <translation>Die Bearbeitungsdatei {0} kann jetzt nicht gespeichert werden ({1}); es wurde nichts geschrieben. Schließen Sie das Programm, das sie geöffnet hält, und speichern Sie erneut.</translation>
        </message>
        <message>
            <source>The edits cannot be read; they are shown read-only and never written. {0}</source>
            <extracomment>plugin/widgets/edit_session.py:168</extracomment>
            <translation>Die Bearbeitungen können nicht gelesen werden; sie werden schreibgeschützt angezeigt und nie geschrieben. {0}</translation>
        </message>
        <message>
            <source>The edits file {0} is read-only ({1}); make it writable to edit.</source>
            <extracomment>plugin/widgets/edit_session.py:180</extracomment>
            <translation>Die Bearbeitungsdatei {0} ist schreibgeschützt ({1}); machen Sie sie beschreibbar, um zu bearbeiten.</translation>
        </message>
        <message>
            <source>The edits file {0} is locked or unreadable ({1}); close the program that holds it and open the project again.</source>
            <extracomment>plugin/widgets/edit_session.py:183</extracomment>
            <translation>Die Bearbeitungsdatei {0} ist gesperrt oder unlesbar ({1}); schließen Sie das Programm, das sie geöffnet hält, und öffnen Sie das Projekt erneut.</translation>
        </message>
        <message>
            <source>Use</source>
            <extracomment>plugin/widgets/georef_review.py:46</extracomment>
            <translation>Verwenden</translation>
        </message>
        <message>
            <source>Role</source>
            <extracomment>plugin/widgets/georef_review.py:46</extracomment>
            <translation>Rolle</translation>
        </message>
        <message>
            <source>Pair</source>
            <extracomment>plugin/widgets/georef_review.py:46</extracomment>
            <translation>Paar</translation>
        </message>
        <message>
            <source>Column</source>
            <extracomment>plugin/widgets/georef_review.py:46</extracomment>
            <translation>Spalte</translation>
        </message>
        <message>
            <source>Row</source>
            <extracomment>plugin/widgets/georef_review.py:46</extracomment>
            <translation>Zeile</translation>
        </message>
        <message>
            <source>dX [px]</source>
            <extracomment>plugin/widgets/georef_review.py:47</extracomment>
            <translation>dX [px]</translation>
        </message>
        <message>
            <source>dY [px]</source>
            <extracomment>plugin/widgets/georef_review.py:47</extracomment>
            <translation>dY [px]</translation>
        </message>
        <message>
            <source>Residual [px]</source>
            <extracomment>plugin/widgets/georef_review.py:47</extracomment>
            <translation>Restfehler [px]</translation>
        </message>
        <message>
            <source>Residual [m]</source>
            <extracomment>plugin/widgets/georef_review.py:47</extracomment>
            <translation>Restfehler [m]</translation>
        </message>
        <message>
            <source>Leave-one-out [m]</source>
            <extracomment>plugin/widgets/georef_review.py:48</extracomment>
            <translation>Ohne diesen Punkt [m]</translation>
        </message>
        <message>
            <source>Reject</source>
            <extracomment>plugin/widgets/georef_review.py:53</extracomment>
            <translation>Verwerfen</translation>
        </message>
        <message>
            <source>Image object</source>
            <extracomment>plugin/widgets/georef_review.py:53</extracomment>
            <translation>Bildobjekt</translation>
        </message>
        <message>
            <source>Reference object</source>
            <extracomment>plugin/widgets/georef_review.py:53</extracomment>
            <translation>Referenzobjekt</translation>
        </message>
        <message>
            <source>Segmentation run</source>
            <extracomment>plugin/widgets/georef_review.py:54</extracomment>
            <translation>Segmentierungslauf</translation>
        </message>
        <message>
            <source>Threshold [DN]</source>
            <extracomment>plugin/widgets/georef_review.py:54</extracomment>
            <translation>Schwellwert [GW]</translation>
        </message>
        <message>
            <source>ICP RMS [px]</source>
            <extracomment>plugin/widgets/georef_review.py:54</extracomment>
            <translation>ICP-RMS [px]</translation>
        </message>
        <message>
            <source>Converged</source>
            <extracomment>plugin/widgets/georef_review.py:55</extracomment>
            <translation>Konvergiert</translation>
        </message>
        <message>
            <source>the control points cover {hull_pct:.0f} % of the image (needs ≥ {min_hull_pct:.0f} %) and {quadrants} of 4 quadrants (needs ≥ {min_quadrants})</source>
            <extracomment>plugin/widgets/georef_review.py:76</extracomment>
            <translation>die Passpunkte überdecken {hull_pct:.0f} % des Bildes (nötig ≥ {min_hull_pct:.0f} %) und {quadrants} von 4 Quadranten (nötig ≥ {min_quadrants})</translation>
        </message>
        <message>
            <source>too few control points for a held-out check</source>
            <extracomment>plugin/widgets/georef_review.py:79</extracomment>
            <translation>zu wenige Passpunkte für eine Prüfung mit zurückgehaltenen Punkten</translation>
        </message>
        <message>
            <source>the corners disagree by {corner_px:.1f} px between transforms of halves of the control points (at most {max_px:g} px)</source>
            <extracomment>plugin/widgets/georef_review.py:80</extracomment>
            <translation>die Ecken weichen zwischen den Transformationen aus je einer Hälfte der Passpunkte um {corner_px:.1f} px ab (höchstens {max_px:g} px)</translation>
        </message>
        <message>
            <source>control points held out quadrant by quadrant are predicted with an RMSE of {rmse_px:.1f} px (at most {max_px:g} px)</source>
            <extracomment>plugin/widgets/georef_review.py:82</extracomment>
            <translation>Quadrant für Quadrant zurückgehaltene Passpunkte werden mit einem RMSE von {rmse_px:.1f} px vorhergesagt (höchstens {max_px:g} px)</translation>
        </message>
        <message>
            <source>no image–reference agreement could be measured (the reference does not reach into the image)</source>
            <extracomment>plugin/widgets/georef_review.py:84</extracomment>
            <translation>keine Übereinstimmung von Bild und Referenz messbar (die Referenz reicht nicht ins Bild)</translation>
        </message>
        <message>
            <source>image and reference do not agree: edge peak ratio {peak:.2f} (needs ≥ {need:g})</source>
            <extracomment>plugin/widgets/georef_review.py:86</extracomment>
            <translation>Bild und Referenz stimmen nicht überein: Kantenspitzenverhältnis {peak:.2f} (nötig ≥ {need:g})</translation>
        </message>
        <message>
            <source>image and reference do not agree: correlation peak margin {peak:.2f} (needs ≥ {need:g})</source>
            <extracomment>plugin/widgets/georef_review.py:88</extracomment>
            <translation>Bild und Referenz stimmen nicht überein: Korrelationsvorsprung der Spitze {peak:.2f} (nötig ≥ {need:g})</translation>
        </message>
        <message>
            <source>image and reference agree best {offset_px:.1f} px away from the result (at most {max_px:g} px)</source>
            <extracomment>plugin/widgets/georef_review.py:90</extracomment>
            <translation>Bild und Referenz stimmen {offset_px:.1f} px neben dem Ergebnis am besten überein (höchstens {max_px:g} px)</translation>
        </message>
        <message>
            <source>image and reference agree best {misfit_px:.1f} px away from the result at an image corner (extrapolated from the quadrants; at most {max_px:g} px)</source>
            <extracomment>plugin/widgets/georef_review.py:92</extracomment>
            <translation>Bild und Referenz stimmen an einer Bildecke {misfit_px:.1f} px neben dem Ergebnis am besten überein (aus den Quadranten extrapoliert; höchstens {max_px:g} px)</translation>
        </message>
        <message>
            <source>image and reference agree best away from the result in the {quadrants} (at most {max_px:g} px)</source>
            <extracomment>plugin/widgets/georef_review.py:95</extracomment>
            <translation>Bild und Referenz stimmen neben dem Ergebnis am besten überein im {quadrants} (höchstens {max_px:g} px)</translation>
        </message>
        <message>
            <source>building footprints cannot confirm a result of the area-based search (roof edges displaced by relief, walls and cast shadows agree with the footprints a few pixels apart)</source>
            <extracomment>plugin/widgets/georef_review.py:97</extracomment>
            <translation>Gebäudegrundrisse können ein Ergebnis der flächenbasierten Suche nicht bestätigen (durch Reliefversatz verschobene Dachkanten, Wände und Schlagschatten passen an mehreren, wenige Pixel auseinanderliegenden Stellen zu den Grundrissen)</translation>
        </message>
        <message>
            <source>top left quadrant ({0} px)</source>
            <extracomment>plugin/widgets/georef_review.py:110</extracomment>
            <translation>Quadranten oben links ({0} px)</translation>
        </message>
        <message>
            <source>top right quadrant ({0} px)</source>
            <extracomment>plugin/widgets/georef_review.py:110</extracomment>
            <translation>Quadranten oben rechts ({0} px)</translation>
        </message>
        <message>
            <source>bottom left quadrant ({0} px)</source>
            <extracomment>plugin/widgets/georef_review.py:111</extracomment>
            <translation>Quadranten unten links ({0} px)</translation>
        </message>
        <message>
            <source>bottom right quadrant ({0} px)</source>
            <extracomment>plugin/widgets/georef_review.py:111</extracomment>
            <translation>Quadranten unten rechts ({0} px)</translation>
        </message>
        <message>
            <source>edge peak ratio {0}</source>
            <extracomment>plugin/widgets/georef_review.py:150</extracomment>
            <translation>Kantenspitzenverhältnis {0}</translation>
        </message>
        <message>
            <source>correlation peak margin {0}</source>
            <extracomment>plugin/widgets/georef_review.py:151</extracomment>
            <translation>Korrelationsvorsprung der Spitze {0}</translation>
        </message>
        <message>
            <source>Evidence of the automatic result:</source>
            <extracomment>plugin/widgets/georef_review.py:160; plugin/widgets/georef_review.py:162</extracomment>
            <translation>Belege des automatischen Ergebnisses:</translation>
        </message>
        <message>
            <source>Figures:</source>
            <extracomment>plugin/widgets/georef_review.py:162</extracomment>
            <translation>Kennzahlen:</translation>
        </message>
        <message>
            <source>Add control point</source>
            <extracomment>plugin/widgets/georef_review.py:171</extracomment>
            <translation>Passpunkt hinzufügen</translation>
        </message>
        <message>
            <source>Drop outliers (&gt; 3 σ0)</source>
            <extracomment>plugin/widgets/georef_review.py:233</extracomment>
            <translation>Ausreißer entfernen (&gt; 3 σ0)</translation>
        </message>
        <message>
            <source>Control points</source>
            <extracomment>plugin/widgets/georef_review.py:260</extracomment>
            <translation>Passpunkte</translation>
        </message>
        <message>
            <source>Object pairs</source>
            <extracomment>plugin/widgets/georef_review.py:261</extracomment>
            <translation>Objektpaare</translation>
        </message>
        <message>
            <source>Add control point…</source>
            <extracomment>plugin/widgets/georef_review.py:268</extracomment>
            <translation>Passpunkt hinzufügen…</translation>
        </message>
        <message>
            <source>Import check points…</source>
            <extracomment>plugin/widgets/georef_review.py:269</extracomment>
            <translation>Kontrollpunkte importieren…</translation>
        </message>
        <message>
            <source>Independent check points from a CSV/TXT file with a header: col,row,x,y (pixel centres at whole numbers) or pixel,line,mapX,mapY (a QGIS .points file); they are never used in the fit.</source>
            <extracomment>plugin/widgets/georef_review.py:270</extracomment>
            <translation>Unabhängige Kontrollpunkte aus einer CSV-/TXT-Datei mit Kopfzeile: col,row,x,y (Pixelmitten auf ganzen Zahlen) oder pixel,line,mapX,mapY (eine .points-Datei von QGIS); sie gehen nie in die Ausgleichung ein.</translation>
        </message>
        <message>
            <source>Switch off largest residual</source>
            <extracomment>plugin/widgets/georef_review.py:274</extracomment>
            <translation>Größten Restfehler abschalten</translation>
        </message>
        <message>
            <source>Write the control points, the georeferenced image and the report again (the automatic result is kept as report_auto.json).</source>
            <extracomment>plugin/widgets/georef_review.py:276</extracomment>
            <translation>Passpunkte, georeferenziertes Bild und Bericht neu schreiben (das automatische Ergebnis bleibt als report_auto.json erhalten).</translation>
        </message>
        <message>
            <source>Writing the georeferenced image …</source>
            <extracomment>plugin/widgets/georef_review.py:595</extracomment>
            <translation>Georeferenziertes Bild wird geschrieben …</translation>
        </message>
        <message>
            <source>Output folder of a georeferencing</source>
            <extracomment>plugin/widgets/georef_review.py:641</extracomment>
            <translation>Ausgabeordner einer Georeferenzierung</translation>
        </message>
        <message>
            <source>yes</source>
            <extracomment>plugin/widgets/georef_review.py:677</extracomment>
            <translation>ja</translation>
        </message>
        <message>
            <source>no</source>
            <extracomment>plugin/widgets/georef_review.py:677</extracomment>
            <translation>nein</translation>
        </message>
        <message>
            <source>control point</source>
            <extracomment>plugin/widgets/georef_review.py:60</extracomment>
            <translation>Passpunkt</translation>
        </message>
        <message>
            <source>outlier (dropped)</source>
            <extracomment>plugin/widgets/georef_review.py:60</extracomment>
            <translation>Ausreißer (entfernt)</translation>
        </message>
        <message>
            <source>check point (off)</source>
            <extracomment>plugin/widgets/georef_review.py:61</extracomment>
            <translation>Kontrollpunkt (aus)</translation>
        </message>
        <message>
            <source>pair rejected</source>
            <extracomment>plugin/widgets/georef_review.py:61</extracomment>
            <translation>Paar verworfen</translation>
        </message>
        <message>
            <source>check (independent)</source>
            <extracomment>plugin/widgets/georef_review.py:62</extracomment>
            <translation>Kontrollpunkt (unabhängig)</translation>
        </message>
        <message>
            <source>manual</source>
            <extracomment>plugin/widgets/georef_review.py:67</extracomment>
            <translation>manuell</translation>
        </message>
        <message>
            <source>search grid</source>
            <extracomment>plugin/widgets/georef_review.py:68</extracomment>
            <translation>Suchraster</translation>
        </message>
        <message>
            <source>Verified: yes</source>
            <extracomment>plugin/widgets/georef_review.py:137</extracomment>
            <translation>Bestätigt: ja</translation>
        </message>
        <message>
            <source>UNVERIFIED</source>
            <extracomment>plugin/widgets/georef_review.py:139</extracomment>
            <translation>UNBESTÄTIGT</translation>
        </message>
        <message>
            <source>control points from a grid through the search transform</source>
            <extracomment>plugin/widgets/georef_review.py:148</extracomment>
            <translation>Passpunkte aus einem Raster durch die Transformation der Suche</translation>
        </message>
        <message>
            <source>Image column [px]</source>
            <extracomment>plugin/widgets/georef_review.py:174</extracomment>
            <translation>Bildspalte [px]</translation>
        </message>
        <message>
            <source>Image row [px]</source>
            <extracomment>plugin/widgets/georef_review.py:175</extracomment>
            <translation>Bildzeile [px]</translation>
        </message>
        <message>
            <source>Map X</source>
            <extracomment>plugin/widgets/georef_review.py:176</extracomment>
            <translation>Karte X</translation>
        </message>
        <message>
            <source>Map Y</source>
            <extracomment>plugin/widgets/georef_review.py:177</extracomment>
            <translation>Karte Y</translation>
        </message>
        <message>
            <source>Transform:</source>
            <extracomment>plugin/widgets/georef_review.py:242</extracomment>
            <translation>Transformation:</translation>
        </message>
        <message>
            <source>Skipped check points outside the image ({0}): {1}.</source>
            <extracomment>plugin/widgets/georef_review.py:447</extracomment>
            <translation>Kontrollpunkte außerhalb des Bildes übersprungen ({0}): {1}.</translation>
        </message>
        <message>
            <source>RMSE &lt;b&gt;{0:.3f} px&lt;/b&gt; = {1:.3f} m, σ0 {2:.3f} m; {3} of {4} points in the fit</source>
            <extracomment>plugin/widgets/georef_review.py:503</extracomment>
            <translation>RMSE &lt;b&gt;{0:.3f} px&lt;/b&gt; = {1:.3f} m, σ0 {2:.3f} m; {3} von {4} Punkten in der Ausgleichung</translation>
        </message>
        <message>
            <source>Discard the changes that are not saved?</source>
            <extracomment>plugin/widgets/georef_review.py:624</extracomment>
            <translation>Nicht gespeicherte Änderungen verwerfen?</translation>
        </message>
        <message>
            <source>control points cover {0} % of the image, {1} of 4 quadrants</source>
            <extracomment>plugin/widgets/georef_review.py:142</extracomment>
            <translation>Passpunkte überdecken {0} % des Bildes, {1} von 4 Quadranten</translation>
        </message>
        <message>
            <source>quadrant offsets {0} px</source>
            <extracomment>plugin/widgets/georef_review.py:156</extracomment>
            <translation>Versätze je Quadrant {0} px</translation>
        </message>
        <message>
            <source>corner misfit {0} px</source>
            <extracomment>plugin/widgets/georef_review.py:158</extracomment>
            <translation>Fehlanpassung an den Ecken {0} px</translation>
        </message>
        <message>
            <source>Map coordinates in {0}; pixel centres at whole numbers, the top-left pixel is (0, 0).</source>
            <extracomment>plugin/widgets/georef_review.py:183</extracomment>
            <translation>Kartenkoordinaten in {0}; Pixelmitten auf ganzen Zahlen, das Pixel oben links ist (0, 0).</translation>
        </message>
        <message>
            <source>Review georeferencing — {0}</source>
            <extracomment>plugin/widgets/georef_review.py:225</extracomment>
            <translation>Georeferenzierung prüfen — {0}</translation>
        </message>
        <message>
            <source>Import check points</source>
            <extracomment>plugin/widgets/georef_review.py:422</extracomment>
            <translation>Kontrollpunkte importieren</translation>
        </message>
        <message>
            <source>Check points (*.csv *.txt *.points);;All files (*)</source>
            <extracomment>plugin/widgets/georef_review.py:423</extracomment>
            <translation>Kontrollpunkte (*.csv *.txt *.points);;Alle Dateien (*)</translation>
        </message>
        <message>
            <source>; {0} check points: RMSE {1:.3f} m</source>
            <extracomment>plugin/widgets/georef_review.py:507</extracomment>
            <translation>; {0} Kontrollpunkte: RMSE {1:.3f} m</translation>
        </message>
        <message>
            <source>; {0} independent check points: RMSE &lt;b&gt;{1:.3f} px&lt;/b&gt; = {2:.3f} m</source>
            <extracomment>plugin/widgets/georef_review.py:509</extracomment>
            <translation>; {0} unabhängige Kontrollpunkte: RMSE &lt;b&gt;{1:.3f} px&lt;/b&gt; = {2:.3f} m</translation>
        </message>
        <message>
            <source>not saved</source>
            <extracomment>plugin/widgets/georef_review.py:513</extracomment>
            <translation>nicht gespeichert</translation>
        </message>
        <message>
            <source>corners disagree by {0} px between halves</source>
            <extracomment>plugin/widgets/georef_review.py:145</extracomment>
            <translation>Ecken weichen zwischen den Hälften um {0} px ab</translation>
        </message>
        <message>
            <source>at {0} px</source>
            <extracomment>plugin/widgets/georef_review.py:153</extracomment>
            <translation>bei {0} px</translation>
        </message>
        <message>
            <source>Residuals (×{0:g})</source>
            <extracomment>plugin/widgets/georef_review.py:547</extracomment>
            <translation>Restfehler (×{0:g})</translation>
        </message>
        <message>
            <source>control point ({0})</source>
            <extracomment>plugin/widgets/georef_review.py:567</extracomment>
            <translation>Passpunkt ({0})</translation>
        </message>
        <message>
            <source>Z draped</source>
            <extracomment>plugin/widgets/map_edit_tools.py:364</extracomment>
            <translation>Z von der Oberfläche</translation>
        </message>
        <message>
            <source>Z typed</source>
            <extracomment>plugin/widgets/map_edit_tools.py:364</extracomment>
            <translation>Z eingegeben</translation>
        </message>
        <message>
            <source>Z interpolated</source>
            <extracomment>plugin/widgets/map_edit_tools.py:365</extracomment>
            <translation>Z interpoliert</translation>
        </message>
        <message>
            <source>The surface that gives new points and breaklines their heights</source>
            <extracomment>plugin/widgets/map_edit_tools.py:398</extracomment>
            <translation>Die Oberfläche, aus der neue Punkte und Bruchkanten ihre Höhen erhalten</translation>
        </message>
        <message>
            <source>Breakline heights: draped on the surface, typed at every vertex, or typed at the ends and interpolated between</source>
            <extracomment>plugin/widgets/map_edit_tools.py:405</extracomment>
            <translation>Höhen der Bruchkanten: auf die Oberfläche gelegt, an jedem Stützpunkt eingegeben oder an den Enden eingegeben und dazwischen interpoliert</translation>
        </message>
        <message>
            <source>PhotoDEM edit tools</source>
            <extracomment>plugin/widgets/map_edit_tools.py:412</extracomment>
            <translation>PhotoDEM-Bearbeitungswerkzeuge</translation>
        </message>
        <message>
            <source>New heights of every breakline and point from the chosen surface (one undo step)</source>
            <extracomment>plugin/widgets/map_edit_tools.py:418</extracomment>
            <translation>Neue Höhen aller Bruchkanten und Punkte aus der gewählten Oberfläche (ein Rückgängig-Schritt)</translation>
        </message>
        <message>
            <source>Save edits</source>
            <extracomment>plugin/widgets/map_edit_tools.py:421</extracomment>
            <translation>Bearbeitungen speichern</translation>
        </message>
        <message>
            <source>Open a PhotoDEM project first (File → Open project…).</source>
            <extracomment>plugin/widgets/map_edit_tools.py:123; plugin/widgets/map_edit_tools.py:521</extracomment>
            <translation>Öffnen Sie zuerst ein PhotoDEM-Projekt (Datei → Projekt öffnen…).</translation>
        </message>
        <message>
            <source>Vertices</source>
            <extracomment>plugin/widgets/map_edit_tools.py:414</extracomment>
            <translation>Stützpunkte</translation>
        </message>
        <message>
            <source>(no DSM or DTM yet)</source>
            <extracomment>plugin/widgets/map_edit_tools.py:585</extracomment>
            <translation>(noch kein DOM oder DGM)</translation>
        </message>
        <message>
            <source>Edits saved to {0}.</source>
            <extracomment>plugin/widgets/map_edit_tools.py:636</extracomment>
            <translation>Bearbeitungen gespeichert in {0}.</translation>
        </message>
        <message>
            <source>The surface '{0}' is not a file.</source>
            <extracomment>plugin/widgets/map_edit_tools.py:106</extracomment>
            <translation>Die Oberfläche '{0}' ist keine Datei.</translation>
        </message>
        <message>
            <source>The edits are read-only: {0}</source>
            <extracomment>plugin/widgets/map_edit_tools.py:126</extracomment>
            <translation>Die Bearbeitungen sind schreibgeschützt: {0}</translation>
        </message>
        <message>
            <source>Opacity of the selected layer</source>
            <extracomment>plugin/widgets/map_layers.py:77</extracomment>
            <translation>Deckkraft des gewählten Layers</translation>
        </message>
        <message>
            <source>Opacity</source>
            <extracomment>plugin/widgets/map_layers.py:78</extracomment>
            <translation>Deckkraft</translation>
        </message>
        <message>
            <source>Move the layer up</source>
            <extracomment>plugin/widgets/map_layers.py:79</extracomment>
            <translation>Layer nach oben verschieben</translation>
        </message>
        <message>
            <source>Move the layer down</source>
            <extracomment>plugin/widgets/map_layers.py:81</extracomment>
            <translation>Layer nach unten verschieben</translation>
        </message>
        <message>
            <source>Zoom to layer</source>
            <extracomment>plugin/widgets/map_layers.py:243; plugin/widgets/map_layers.py:83</extracomment>
            <translation>Auf Layer zoomen</translation>
        </message>
        <message>
            <source>Remove layer</source>
            <extracomment>plugin/widgets/map_layers.py:252; plugin/widgets/map_layers.py:84</extracomment>
            <translation>Layer entfernen</translation>
        </message>
        <message>
            <source>Move up</source>
            <extracomment>plugin/widgets/map_layers.py:244</extracomment>
            <translation>Nach oben</translation>
        </message>
        <message>
            <source>Move down</source>
            <extracomment>plugin/widgets/map_layers.py:246</extracomment>
            <translation>Nach unten</translation>
        </message>
        <message>
            <source>Build overviews</source>
            <extracomment>plugin/widgets/map_layers.py:250</extracomment>
            <translation>Übersichten erzeugen</translation>
        </message>
        <message>
            <source>Overviews written to {0}.</source>
            <extracomment>plugin/widgets/map_layers.py:269</extracomment>
            <translation>Übersichten geschrieben nach {0}.</translation>
        </message>
        <message>
            <source>Overviews of {0} not built: {1}</source>
            <extracomment>plugin/widgets/map_layers.py:265</extracomment>
            <translation>Übersichten von {0} nicht erzeugt: {1}</translation>
        </message>
        <message>
            <source>drawn polygon ({0:.0f} m²)</source>
            <extracomment>plugin/widgets/map_qc_tools.py:28</extracomment>
            <translation>gezeichnetes Polygon ({0:.0f} m²)</translation>
        </message>
        <message>
            <source>A point has only this one vertex; delete the feature instead.</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:113</extracomment>
            <translation>Ein Punkt hat nur diesen einen Stützpunkt; löschen Sie stattdessen das Objekt.</translation>
        </message>
        <message>
            <source>Move vertex</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:303</extracomment>
            <translation>Stützpunkt verschieben</translation>
        </message>
        <message>
            <source>Delete vertex</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:316</extracomment>
            <translation>Stützpunkt löschen</translation>
        </message>
        <message>
            <source>Re-drape {0} features</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:463</extracomment>
            <translation>{0} Objekte neu abgreifen</translation>
        </message>
        <message>
            <source>A line needs at least 2 vertices; this one would keep only {0}. Delete the feature instead.</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:115</extracomment>
            <translation>Eine Linie braucht mindestens 2 Stützpunkte; diese behielte nur {0}. Löschen Sie stattdessen das Objekt.</translation>
        </message>
        <message>
            <source>A polygon needs at least 3 vertices; this one would keep only {0}. Delete the feature instead.</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:118</extracomment>
            <translation>Ein Polygon braucht mindestens 3 Stützpunkte; dieses behielte nur {0}. Löschen Sie stattdessen das Objekt.</translation>
        </message>
        <message>
            <source>Edit refused, nothing changed: {0}</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:325</extracomment>
            <translation>Bearbeitung abgelehnt, nichts geändert: {0}</translation>
        </message>
        <message>
            <source>The vertex was not moved: {0}</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:298</extracomment>
            <translation>Der Stützpunkt wurde nicht verschoben: {0}</translation>
        </message>
        <message>
            <source>The vertex was not deleted: {0}</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:313</extracomment>
            <translation>Der Stützpunkt wurde nicht gelöscht: {0}</translation>
        </message>
        <message>
            <source>Nothing re-draped: {0} {1}: {2}</source>
            <extracomment>plugin/widgets/map_vertex_tools.py:452</extracomment>
            <translation>Nichts neu abgegriffen: {0} {1}: {2}</translation>
        </message>
        <message>
            <source>'{0}' has no coordinate reference system: it can only be shown alone, in pixel coordinates.</source>
            <extracomment>plugin/widgets/map_view.py:160</extracomment>
            <translation>„{0}“ hat kein Koordinatenbezugssystem: nur allein anzeigbar, in Pixelkoordinaten.</translation>
        </message>
        <message>
            <source>The map shows a raster in pixel coordinates; '{0}' is georeferenced and cannot be shown with it.</source>
            <extracomment>plugin/widgets/map_view.py:164</extracomment>
            <translation>Die Karte zeigt ein Raster in Pixelkoordinaten; „{0}“ ist georeferenziert und kann nicht zusammen damit angezeigt werden.</translation>
        </message>
        <message>
            <source>Browse</source>
            <extracomment>plugin/widgets/parameter_form.py:65</extracomment>
            <translation>Durchsuchen</translation>
        </message>
        <message>
            <source>All files (*)</source>
            <extracomment>plugin/widgets/parameter_form.py:82; plugin/widgets/parameter_form.py:84</extracomment>
            <translation>Alle Dateien (*)</translation>
        </message>
        <message>
            <source>optional</source>
            <extracomment>plugin/widgets/parameter_form.py:186; plugin/widgets/parameter_form.py:231; plugin/widgets/parameter_form.py:321</extracomment>
            <translation>optional</translation>
        </message>
        <message>
            <source>choose a project first</source>
            <extracomment>plugin/widgets/parameter_form.py:218</extracomment>
            <translation>zuerst ein Projekt wählen</translation>
        </message>
        <message>
            <source>image name</source>
            <extracomment>plugin/widgets/parameter_form.py:218</extracomment>
            <translation>Bildname</translation>
        </message>
        <message>
            <source>Supported files</source>
            <extracomment>plugin/widgets/parameter_form.py:84</extracomment>
            <translation>Unterstützte Dateien</translation>
        </message>
        <message>
            <source>Choose a folder</source>
            <extracomment>plugin/widgets/parameter_form.py:90</extracomment>
            <translation>Ordner wählen</translation>
        </message>
        <message>
            <source>several files, separated by commas</source>
            <extracomment>plugin/widgets/parameter_form.py:153</extracomment>
            <translation>mehrere Dateien, durch Kommas getrennt</translation>
        </message>
        <message>
            <source>required</source>
            <extracomment>plugin/widgets/parameter_form.py:321</extracomment>
            <translation>erforderlich</translation>
        </message>
        <message>
            <source>e.g. EPSG:25832</source>
            <extracomment>plugin/widgets/parameter_form.py:229</extracomment>
            <translation>z. B. EPSG:25832</translation>
        </message>
        <message>
            <source>xmin,ymin,xmax,ymax</source>
            <extracomment>plugin/widgets/parameter_form.py:230</extracomment>
            <translation>xmin,ymin,xmax,ymax</translation>
        </message>
        <message>
            <source>type a name</source>
            <extracomment>plugin/widgets/parameter_form.py:421</extracomment>
            <translation>Namen eingeben</translation>
        </message>
        <message>
            <source>no project found</source>
            <extracomment>plugin/widgets/parameter_form.py:421</extracomment>
            <translation>kein Projekt gefunden</translation>
        </message>
        <message>
            <source>Save as</source>
            <extracomment>plugin/widgets/parameter_form.py:92</extracomment>
            <translation>Speichern unter</translation>
        </message>
        <message>
            <source>Choose files</source>
            <extracomment>plugin/widgets/parameter_form.py:94</extracomment>
            <translation>Dateien wählen</translation>
        </message>
        <message>
            <source>Choose a file</source>
            <extracomment>plugin/widgets/parameter_form.py:97</extracomment>
            <translation>Datei wählen</translation>
        </message>
        <message>
            <source>dtm.tif of a PhotoDEM filter run (its mask.tif beside it)</source>
            <extracomment>plugin/widgets/qc_filter.py:48</extracomment>
            <translation>dtm.tif eines PhotoDEM-Filterlaufs (mit mask.tif daneben)</translation>
        </message>
        <message>
            <source>preset</source>
            <extracomment>plugin/widgets/qc_filter.py:60</extracomment>
            <translation>Voreinstellung</translation>
        </message>
        <message>
            <source>Re-filter area</source>
            <extracomment>plugin/widgets/qc_filter.py:64</extracomment>
            <translation>Gebiet neu filtern</translation>
        </message>
        <message>
            <source>Draw an area, choose a preset and press 'Re-filter area'</source>
            <extracomment>plugin/widgets/qc_filter.py:69</extracomment>
            <translation>Zeichnen Sie ein Gebiet, wählen Sie eine Voreinstellung und drücken Sie „Gebiet neu filtern“</translation>
        </message>
        <message>
            <source>Accept into the DTM</source>
            <extracomment>plugin/widgets/qc_filter.py:151; plugin/widgets/qc_filter.py:75</extracomment>
            <translation>In das DGM übernehmen</translation>
        </message>
        <message>
            <source>Re-filtering the area…</source>
            <extracomment>plugin/widgets/qc_filter.py:97</extracomment>
            <translation>Gebiet wird neu gefiltert…</translation>
        </message>
        <message>
            <source>new − old DTM [m]</source>
            <extracomment>plugin/widgets/qc_filter.py:138</extracomment>
            <translation>neues − altes DGM [m]</translation>
        </message>
        <message>
            <source>Preset</source>
            <extracomment>plugin/widgets/qc_filter.py:55</extracomment>
            <translation>Voreinstellung</translation>
        </message>
        <message>
            <source>Final threshold</source>
            <extracomment>plugin/widgets/qc_filter.py:62</extracomment>
            <translation>Letzte Schwelle</translation>
        </message>
        <message>
            <source>Draw the area to re-filter first.</source>
            <extracomment>plugin/widgets/qc_filter.py:86</extracomment>
            <translation>Zeichnen Sie zuerst das neu zu filternde Gebiet.</translation>
        </message>
        <message>
            <source>Choose the DSM (as DEM) and the DTM it was filtered into.</source>
            <extracomment>plugin/widgets/qc_filter.py:89</extracomment>
            <translation>Wählen Sie das DOM (als DHM) und das daraus gefilterte DGM.</translation>
        </message>
        <message>
            <source>eliminated before</source>
            <extracomment>plugin/widgets/qc_filter.py:124</extracomment>
            <translation>eliminiert vorher</translation>
        </message>
        <message>
            <source>eliminated after</source>
            <extracomment>plugin/widgets/qc_filter.py:125</extracomment>
            <translation>eliminiert nachher</translation>
        </message>
        <message>
            <source>Eliminated in the area: {0} before, {1} with '{2}'; new − old DTM: median {3:+.3f} m, max |Δh| {4:.2f} m. Nothing is written until you accept.</source>
            <extracomment>plugin/widgets/qc_filter.py:107</extracomment>
            <translation>Im Gebiet eliminiert: {0} vorher, {1} mit „{2}“; neues − altes DGM: Median {3:+.3f} m, max. |Δh| {4:.2f} m. Geschrieben wird erst, wenn Sie übernehmen.</translation>
        </message>
        <message>
            <source>The area was written into {0}.</source>
            <extracomment>plugin/widgets/qc_filter.py:161</extracomment>
            <translation>Das Gebiet wurde in {0} geschrieben.</translation>
        </message>
        <message>
            <source>Write the re-filtered area into '{0}' (and its mask)? The cells outside the area stay as they are.</source>
            <extracomment>plugin/widgets/qc_filter.py:152</extracomment>
            <translation>Das neu gefilterte Gebiet in „{0}“ (und seine Maske) schreiben? Die Zellen außerhalb des Gebiets bleiben unverändert.</translation>
        </message>
        <message>
            <source>Rasters (*.tif *.tiff *.vrt *.img);;All files (*)</source>
            <extracomment>plugin/widgets/qc_panel.py:123</extracomment>
            <translation>Raster (*.tif *.tiff *.vrt *.img);;Alle Dateien (*)</translation>
        </message>
        <message>
            <source>PhotoDEM project folder</source>
            <extracomment>plugin/widgets/qc_panel.py:124</extracomment>
            <translation>PhotoDEM-Projektordner</translation>
        </message>
        <message>
            <source>edits and comparisons go into this project</source>
            <extracomment>plugin/widgets/qc_panel.py:125</extracomment>
            <translation>Edits und Vergleiche werden in dieses Projekt geschrieben</translation>
        </message>
        <message>
            <source>Class raster</source>
            <extracomment>plugin/widgets/qc_panel.py:133</extracomment>
            <translation>Klassenraster</translation>
        </message>
        <message>
            <source>further surfaces for profiles, separated by ;</source>
            <extracomment>plugin/widgets/qc_panel.py:136</extracomment>
            <translation>weitere Oberflächen für Profile, getrennt durch ;</translation>
        </message>
        <message>
            <source>Profile also</source>
            <extracomment>plugin/widgets/qc_panel.py:137</extracomment>
            <translation>Im Profil auch</translation>
        </message>
        <message>
            <source>Statistics</source>
            <extracomment>plugin/widgets/qc_panel.py:141</extracomment>
            <translation>Statistik</translation>
        </message>
        <message>
            <source>Profile</source>
            <extracomment>plugin/widgets/qc_panel.py:142; plugin/widgets/qc_panel.py:222</extracomment>
            <translation>Profil</translation>
        </message>
        <message>
            <source>Blunders</source>
            <extracomment>plugin/widgets/qc_panel.py:143</extracomment>
            <translation>Grobe Fehler</translation>
        </message>
        <message>
            <source>Filter review</source>
            <extracomment>plugin/widgets/qc_panel.py:146</extracomment>
            <translation>Filterprüfung</translation>
        </message>
        <message>
            <source>Compare</source>
            <extracomment>plugin/widgets/qc_panel.py:153</extracomment>
            <translation>Vergleichen</translation>
        </message>
        <message>
            <source>Run dem_compare on the whole model and add the difference model to the map</source>
            <extracomment>plugin/widgets/qc_panel.py:154</extracomment>
            <translation>dem_compare für das ganze Modell ausführen und das Differenzmodell zur Karte hinzufügen</translation>
        </message>
        <message>
            <source>Statistics of the area</source>
            <extracomment>plugin/widgets/qc_panel.py:157</extracomment>
            <translation>Statistik des Gebiets</translation>
        </message>
        <message>
            <source>Estimate and remove a horizontal shift and a vertical bias (Nuth &amp; Kääb) on stable terrain first (Compare only).</source>
            <extracomment>plugin/widgets/qc_panel.py:170</extracomment>
            <translation>Zuerst eine Lageverschiebung und einen Höhenversatz (Nuth &amp; Kääb) auf stabilem Gelände schätzen und entfernen (nur beim Vergleichen).</translation>
        </message>
        <message>
            <source>Rasters or polygons (*.tif *.tiff *.gpkg *.shp *.geojson);;All files (*)</source>
            <extracomment>plugin/widgets/qc_panel.py:175</extracomment>
            <translation>Raster oder Polygone (*.tif *.tiff *.gpkg *.shp *.geojson);;Alle Dateien (*)</translation>
        </message>
        <message>
            <source>stable terrain: mask raster or polygons (default: the whole common area)</source>
            <extracomment>plugin/widgets/qc_panel.py:176</extracomment>
            <translation>stabiles Gelände: Maskenraster oder Polygone (Vorgabe: die ganze gemeinsame Fläche)</translation>
        </message>
        <message>
            <source>xmin, ymin, xmax, ymax (reference CRS)</source>
            <extracomment>plugin/widgets/qc_panel.py:191</extracomment>
            <translation>xmin, ymin, xmax, ymax (KBS der Referenz)</translation>
        </message>
        <message>
            <source>Use extent</source>
            <extracomment>plugin/widgets/qc_panel.py:192</extracomment>
            <translation>Ausdehnung verwenden</translation>
        </message>
        <message>
            <source>Draw an area or press 'Statistics of the area'</source>
            <extracomment>plugin/widgets/qc_panel.py:206</extracomment>
            <translation>Zeichnen Sie ein Gebiet oder drücken Sie „Statistik des Gebiets“</translation>
        </message>
        <message>
            <source>x1,y1;x2,y2;… (DEM CRS), or draw a line on the map</source>
            <extracomment>plugin/widgets/qc_panel.py:220</extracomment>
            <translation>x1,y1;x2,y2;… (KBS des DHM) oder eine Linie in der Karte zeichnen</translation>
        </message>
        <message>
            <source>Draw a line on the map</source>
            <extracomment>plugin/widgets/qc_panel.py:228</extracomment>
            <translation>Zeichnen Sie eine Linie in der Karte</translation>
        </message>
        <message>
            <source>Export CSV…</source>
            <extracomment>plugin/widgets/qc_panel.py:233</extracomment>
            <translation>CSV exportieren…</translation>
        </message>
        <message>
            <source>Export PNG…</source>
            <extracomment>plugin/widgets/qc_panel.py:235</extracomment>
            <translation>PNG exportieren…</translation>
        </message>
        <message>
            <source>Find blunders</source>
            <extracomment>plugin/widgets/qc_panel.py:253</extracomment>
            <translation>Grobe Fehler suchen</translation>
        </message>
        <message>
            <source>To exclusion area</source>
            <extracomment>plugin/widgets/qc_panel.py:270</extracomment>
            <translation>Als Ausschlussfläche</translation>
        </message>
        <message>
            <source>To ground point</source>
            <extracomment>plugin/widgets/qc_panel.py:272</extracomment>
            <translation>Als Bodenpunkt</translation>
        </message>
        <message>
            <source>A ground point at the spot's centre with the reference height</source>
            <extracomment>plugin/widgets/qc_panel.py:273</extracomment>
            <translation>Ein Bodenpunkt in der Mitte der Stelle mit der Höhe der Referenz</translation>
        </message>
        <message>
            <source>Click on the map to see every surface's height there.</source>
            <extracomment>plugin/widgets/qc_panel.py:287</extracomment>
            <translation>Klicken Sie in die Karte, um dort die Höhe jeder Oberfläche zu sehen.</translation>
        </message>
        <message>
            <source>Computing statistics…</source>
            <extracomment>plugin/widgets/qc_panel.py:396</extracomment>
            <translation>Statistik wird berechnet…</translation>
        </message>
        <message>
            <source>Comparing…</source>
            <extracomment>plugin/widgets/qc_panel.py:434</extracomment>
            <translation>Vergleiche…</translation>
        </message>
        <message>
            <source>Done.</source>
            <extracomment>plugin/widgets/qc_panel.py:472</extracomment>
            <translation>Fertig.</translation>
        </message>
        <message>
            <source>Searching blunders…</source>
            <extracomment>plugin/widgets/qc_panel.py:506</extracomment>
            <translation>Suche grobe Fehler…</translation>
        </message>
        <message>
            <source>CSV (*.csv)</source>
            <extracomment>plugin/widgets/qc_panel.py:615</extracomment>
            <translation>CSV (*.csv)</translation>
        </message>
        <message>
            <source>PNG image (*.png)</source>
            <extracomment>plugin/widgets/qc_panel.py:615</extracomment>
            <translation>PNG-Bild (*.png)</translation>
        </message>
        <message>
            <source>Export profile</source>
            <extracomment>plugin/widgets/qc_panel.py:616</extracomment>
            <translation>Profil exportieren</translation>
        </message>
        <message>
            <source>Area</source>
            <extracomment>plugin/widgets/qc_panel.py:196</extracomment>
            <translation>Gebiet</translation>
        </message>
        <message>
            <source>|Δh − median| above k × NMAD, k =</source>
            <extracomment>plugin/widgets/qc_panel.py:247</extracomment>
            <translation>|Δh − Median| über k × NMAD, k =</translation>
        </message>
        <message>
            <source>the DEM</source>
            <extracomment>plugin/widgets/qc_panel.py:329</extracomment>
            <translation>das Höhenmodell</translation>
        </message>
        <message>
            <source>the reference</source>
            <extracomment>plugin/widgets/qc_panel.py:329</extracomment>
            <translation>die Referenz</translation>
        </message>
        <message>
            <source>drawn area</source>
            <extracomment>plugin/widgets/qc_panel.py:360</extracomment>
            <translation>gezeichnetes Gebiet</translation>
        </message>
        <message>
            <source>Give the extent as 'xmin, ymin, xmax, ymax'.</source>
            <extracomment>plugin/widgets/qc_panel.py:373</extracomment>
            <translation>Geben Sie die Ausdehnung als „xmin, ymin, xmax, ymax“ an.</translation>
        </message>
        <message>
            <source>Open a project first: the comparison is written into its products folder.</source>
            <extracomment>plugin/widgets/qc_panel.py:421</extracomment>
            <translation>Öffnen Sie zuerst ein Projekt: Der Vergleich wird in seinen Produktordner geschrieben.</translation>
        </message>
        <message>
            <source>A computation is running; wait or cancel it.</source>
            <extracomment>plugin/widgets/qc_panel.py:452</extracomment>
            <translation>Eine Berechnung läuft; warten Sie oder brechen Sie sie ab.</translation>
        </message>
        <message>
            <source>Select a blunder in the list first.</source>
            <extracomment>plugin/widgets/qc_panel.py:525</extracomment>
            <translation>Wählen Sie zuerst einen groben Fehler in der Liste.</translation>
        </message>
        <message>
            <source>Open a project with an edits.gpkg first: the edit goes into it.</source>
            <extracomment>plugin/widgets/qc_panel.py:532</extracomment>
            <translation>Öffnen Sie zuerst ein Projekt mit edits.gpkg: Die Bearbeitung wird dort gespeichert.</translation>
        </message>
        <message>
            <source>The reference has no height at the spot's centre.</source>
            <extracomment>plugin/widgets/qc_panel.py:570</extracomment>
            <translation>Die Referenz hat in der Mitte der Stelle keine Höhe.</translation>
        </message>
        <message>
            <source>Choose the surfaces first.</source>
            <extracomment>plugin/widgets/qc_panel.py:580; plugin/widgets/qc_panel.py:626</extracomment>
            <translation>Wählen Sie zuerst die Oberflächen.</translation>
        </message>
        <message>
            <source>Height [m]</source>
            <extracomment>plugin/widgets/qc_panel.py:632; plugin/widgets/qc_plots.py:170</extracomment>
            <translation>Höhe [m]</translation>
        </message>
        <message>
            <source>extent {0}</source>
            <extracomment>plugin/widgets/qc_panel.py:375</extracomment>
            <translation>Ausdehnung {0}</translation>
        </message>
        <message>
            <source>Area: {0}</source>
            <extracomment>plugin/widgets/qc_panel.py:386</extracomment>
            <translation>Gebiet: {0}</translation>
        </message>
        <message>
            <source>Cancelled.</source>
            <extracomment>plugin/widgets/qc_panel.py:458</extracomment>
            <translation>Abgebrochen.</translation>
        </message>
        <message>
            <source>{0} blunder spots (|Δh − median| &gt; {1:.2f} m).</source>
            <extracomment>plugin/widgets/qc_panel.py:511</extracomment>
            <translation>{0} Stellen mit groben Fehlern (|Δh − Median| &gt; {1:.2f} m).</translation>
        </message>
        <message>
            <source>Written to {0}.</source>
            <extracomment>plugin/widgets/qc_panel.py:543</extracomment>
            <translation>In {0} geschrieben.</translation>
        </message>
        <message>
            <source>{0} stations, {1} breakline crossings, {2} check points</source>
            <extracomment>plugin/widgets/qc_panel.py:594</extracomment>
            <translation>{0} Stationen, {1} Kreuzungen mit Bruchkanten, {2} Kontrollpunkte</translation>
        </message>
        <message>
            <source>At x = {0:.2f}, y = {1:.2f}</source>
            <extracomment>plugin/widgets/qc_panel.py:639</extracomment>
            <translation>Bei x = {0:.2f}, y = {1:.2f}</translation>
        </message>
        <message>
            <source>'{0}' is no PhotoDEM project (no project.toml); choose the project folder.</source>
            <extracomment>plugin/widgets/qc_panel.py:300</extracomment>
            <translation>„{0}“ ist kein PhotoDEM-Projekt (keine project.toml); wählen Sie den Projektordner.</translation>
        </message>
        <message>
            <source>Internal error: {0}</source>
            <extracomment>plugin/widgets/qc_panel.py:478</extracomment>
            <translation>Interner Fehler: {0}</translation>
        </message>
        <message>
            <source>Profile written to {0}.</source>
            <extracomment>plugin/widgets/qc_panel.py:620</extracomment>
            <translation>Profil nach {0} geschrieben.</translation>
        </message>
        <message>
            <source>Choose {0}: '{1}' is not a raster file.</source>
            <extracomment>plugin/widgets/qc_panel.py:332</extracomment>
            <translation>Wählen Sie {0}: „{1}“ ist keine Rasterdatei.</translation>
        </message>
        <message>
            <source>Δh = DEM − reference [m]</source>
            <extracomment>plugin/widgets/qc_plots.py:140</extracomment>
            <translation>Δh = DHM − Referenz [m]</translation>
        </message>
        <message>
            <source>Cells</source>
            <extracomment>plugin/widgets/qc_plots.py:141; plugin/widgets/qc_plots.py:181</extracomment>
            <translation>Zellen</translation>
        </message>
        <message>
            <source>Distance along the line [m]</source>
            <extracomment>plugin/widgets/qc_plots.py:169</extracomment>
            <translation>Abstand entlang der Linie [m]</translation>
        </message>
        <message>
            <source>Area [m²]</source>
            <extracomment>plugin/widgets/qc_plots.py:181</extracomment>
            <translation>Fläche [m²]</translation>
        </message>
        <message>
            <source>Max. Δh [m]</source>
            <extracomment>plugin/widgets/qc_plots.py:181</extracomment>
            <translation>Max. Δh [m]</translation>
        </message>
        <message>
            <source>Mean Δh [m]</source>
            <extracomment>plugin/widgets/qc_plots.py:181</extracomment>
            <translation>Mittleres Δh [m]</translation>
        </message>
        <message>
            <source>Count</source>
            <extracomment>plugin/widgets/qc_plots.py:27; plugin/widgets/qc_plots.py:81</extracomment>
            <translation>Anzahl</translation>
        </message>
        <message>
            <source>Mean</source>
            <extracomment>plugin/widgets/qc_plots.py:27; plugin/widgets/qc_plots.py:81</extracomment>
            <translation>Mittelwert</translation>
        </message>
        <message>
            <source>Median</source>
            <extracomment>plugin/widgets/qc_plots.py:28; plugin/widgets/qc_plots.py:82</extracomment>
            <translation>Median</translation>
        </message>
        <message>
            <source>Std. deviation</source>
            <extracomment>plugin/widgets/qc_plots.py:28</extracomment>
            <translation>Standardabweichung</translation>
        </message>
        <message>
            <source>Minimum</source>
            <extracomment>plugin/widgets/qc_plots.py:29</extracomment>
            <translation>Minimum</translation>
        </message>
        <message>
            <source>Maximum</source>
            <extracomment>plugin/widgets/qc_plots.py:30</extracomment>
            <translation>Maximum</translation>
        </message>
        <message>
            <source>68 % quantile of |Δh|</source>
            <extracomment>plugin/widgets/qc_plots.py:30</extracomment>
            <translation>68-%-Quantil von |Δh|</translation>
        </message>
        <message>
            <source>90 % quantile of |Δh|</source>
            <extracomment>plugin/widgets/qc_plots.py:31</extracomment>
            <translation>90-%-Quantil von |Δh|</translation>
        </message>
        <message>
            <source>95 % quantile of |Δh|</source>
            <extracomment>plugin/widgets/qc_plots.py:31</extracomment>
            <translation>95-%-Quantil von |Δh|</translation>
        </message>
        <message>
            <source>99 % quantile of |Δh|</source>
            <extracomment>plugin/widgets/qc_plots.py:32</extracomment>
            <translation>99-%-Quantil von |Δh|</translation>
        </message>
        <message>
            <source>Within ±0.25 m</source>
            <extracomment>plugin/widgets/qc_plots.py:33</extracomment>
            <translation>Innerhalb ±0,25 m</translation>
        </message>
        <message>
            <source>Within ±0.5 m</source>
            <extracomment>plugin/widgets/qc_plots.py:33; plugin/widgets/qc_plots.py:82</extracomment>
            <translation>Innerhalb ±0,5 m</translation>
        </message>
        <message>
            <source>Within ±1 m</source>
            <extracomment>plugin/widgets/qc_plots.py:34</extracomment>
            <translation>Innerhalb ±1 m</translation>
        </message>
        <message>
            <source>Statistic</source>
            <extracomment>plugin/widgets/qc_plots.py:58</extracomment>
            <translation>Kennzahl</translation>
        </message>
        <message>
            <source>Value</source>
            <extracomment>plugin/widgets/qc_plots.py:58; plugin/widgets/run_panel.py:68</extracomment>
            <translation>Wert</translation>
        </message>
        <message>
            <source>Class</source>
            <extracomment>plugin/widgets/qc_plots.py:78</extracomment>
            <translation>Klasse</translation>
        </message>
        <message>
            <source>Slope</source>
            <extracomment>plugin/widgets/qc_plots.py:79</extracomment>
            <translation>Neigung</translation>
        </message>
        <message>
            <source>Grouping</source>
            <extracomment>plugin/widgets/qc_plots.py:81</extracomment>
            <translation>Gruppierung</translation>
        </message>
        <message>
            <source>Group</source>
            <extracomment>plugin/widgets/qc_plots.py:81</extracomment>
            <translation>Gruppe</translation>
        </message>
        <message>
            <source>No differences in this area</source>
            <extracomment>plugin/widgets/qc_plots.py:124</extracomment>
            <translation>Keine Differenzen in diesem Gebiet</translation>
        </message>
        <message>
            <source>check point</source>
            <extracomment>plugin/widgets/qc_plots.py:163</extracomment>
            <translation>Kontrollpunkt</translation>
        </message>
        <message>
            <source>line vertices (Z)</source>
            <extracomment>plugin/widgets/qc_plots.py:167</extracomment>
            <translation>Stützpunkte der Linie (Z)</translation>
        </message>
        <message>
            <source>Profile: {0:.1f} m, spacing {1:g} m</source>
            <extracomment>plugin/widgets/qc_plots.py:171</extracomment>
            <translation>Profil: {0:.1f} m, Abstand {1:g} m</translation>
        </message>
        <message>
            <source>median {0:.3f} m</source>
            <extracomment>plugin/widgets/qc_plots.py:134</extracomment>
            <translation>Median {0:.3f} m</translation>
        </message>
        <message>
            <source>{0} cells outside the plot</source>
            <extracomment>plugin/widgets/qc_plots.py:139</extracomment>
            <translation>{0} Zellen außerhalb der Grafik</translation>
        </message>
        <message>
            <source>Δh histogram: {0} cells, NMAD {1:.3f} m</source>
            <extracomment>plugin/widgets/qc_plots.py:138</extracomment>
            <translation>Δh-Histogramm: {0} Zellen, NMAD {1:.3f} m</translation>
        </message>
        <message>
            <source>nodata</source>
            <extracomment>plugin/widgets/raster_tiles.py:266</extracomment>
            <translation>NoData</translation>
        </message>
        <message>
            <source>The log of the run appears here.</source>
            <extracomment>plugin/widgets/run_panel.py:63</extracomment>
            <translation>Hier erscheint das Protokoll des Laufs.</translation>
        </message>
        <message>
            <source>Open report</source>
            <extracomment>plugin/widgets/run_panel.py:79</extracomment>
            <translation>Bericht öffnen</translation>
        </message>
        <message>
            <source>Result</source>
            <extracomment>plugin/widgets/run_panel.py:94</extracomment>
            <translation>Ergebnis</translation>
        </message>
        <message>
            <source>Finished.</source>
            <extracomment>plugin/widgets/run_panel.py:183</extracomment>
            <translation>Fertig.</translation>
        </message>
        <message>
            <source>Output</source>
            <extracomment>plugin/widgets/run_panel.py:68</extracomment>
            <translation>Ausgabe</translation>
        </message>
        <message>
            <source>Show on map</source>
            <extracomment>plugin/widgets/run_panel.py:233</extracomment>
            <translation>Auf Karte zeigen</translation>
        </message>
        <message>
            <source>Unexpected error (please report it):</source>
            <extracomment>plugin/widgets/run_panel.py:190</extracomment>
            <translation>Unerwarteter Fehler (bitte melden):</translation>
        </message>
        <message>
            <source>Undo</source>
            <extracomment>plugin/widgets/undo_history.py:21; plugin/widgets/undo_history.py:48</extracomment>
            <translation>Rückgängig</translation>
        </message>
        <message>
            <source>Redo</source>
            <extracomment>plugin/widgets/undo_history.py:22; plugin/widgets/undo_history.py:49</extracomment>
            <translation>Wiederholen</translation>
        </message>
        <message>
            <source>Undo the last edit (Ctrl+Z)</source>
            <extracomment>plugin/widgets/undo_history.py:27</extracomment>
            <translation>Letzte Bearbeitung rückgängig machen (Strg+Z)</translation>
        </message>
        <message>
            <source>Redo the edit undone last (Ctrl+Y)</source>
            <extracomment>plugin/widgets/undo_history.py:28</extracomment>
            <translation>Zuletzt rückgängig gemachte Bearbeitung wiederholen (Strg+Y)</translation>
        </message>
        <message>
            <source>&lt;empty&gt;</source>
            <extracomment>plugin/widgets/undo_history.py:47</extracomment>
            <translation>&lt;leer&gt;</translation>
        </message>
        <message>
            <source>No project open.</source>
            <extracomment>plugin/widgets/undo_history.py:97</extracomment>
            <translation>Kein Projekt geöffnet.</translation>
        </message>
        <message>
            <source>Unsaved edits.</source>
            <extracomment>plugin/widgets/undo_history.py:101</extracomment>
            <translation>Ungespeicherte Bearbeitungen.</translation>
        </message>
        <message>
            <source>All edits saved.</source>
            <extracomment>plugin/widgets/undo_history.py:103</extracomment>
            <translation>Alle Bearbeitungen gespeichert.</translation>
        </message>
        <message>
            <source>Fewer than 10 DSM cells are left for the linear prediction (all no data or inside 'remove' exclusion areas); check the input and the exclusion areas.</source>
            <extracomment>algorithms/filtering/linear_prediction.py:721</extracomment>
            <translation>Für die lineare Prädiktion bleiben weniger als 10 DOM-Zellen (alle ohne Daten oder in Ausschlussflächen mit 'remove'); prüfen Sie die Eingabe und die Ausschlussflächen.</translation>
        </message>
        <message>
            <source>The DSM holds no height (every cell is nodata).</source>
            <extracomment>algorithms/filtering/lowpass.py:567; algorithms/filtering/lowpass.py:646</extracomment>
            <translation>Das DOM enthält keine Höhe (jede Zelle ist NoData).</translation>
        </message>
        <message>
            <source>Unknown preset '{name}'; use one of {options}.</source>
            <extracomment>algorithms/filtering/presets.py:200</extracomment>
            <translation>Unbekannte Voreinstellung '{name}'; verwenden Sie eine von {options}.</translation>
        </message>
        <message>
            <source>The DSM '{name}' holds no height (every cell is nodata); check the input.</source>
            <extracomment>algorithms/filtering/surface_input.py:199</extracomment>
            <translation>Das DOM '{name}' enthält keine Höhe (jede Zelle ist NoData); prüfen Sie die Eingabe.</translation>
        </message>
        <message>
            <source>The DSM '{name}' has only {count} cells with a height; a filter needs at least {minimum}.</source>
            <extracomment>algorithms/filtering/surface_input.py:202</extracomment>
            <translation>Das DOM '{name}' hat nur {count} Zellen mit einer Höhe; ein Filter braucht mindestens {minimum}.</translation>
        </message>
        <message>
            <source>'{name}' has only {count} valid point(s); a filter needs at least {minimum}.</source>
            <extracomment>algorithms/filtering/surface_input.py:302</extracomment>
            <translation>'{name}' hat nur {count} gültige(n) Punkt(e); ein Filter braucht mindestens {minimum}.</translation>
        </message>
        <message>
            <source>A {spacing:g} m grid over the points of '{name}' would have more than 400 million cells; give a larger spacing.</source>
            <extracomment>algorithms/filtering/surface_input.py:323</extracomment>
            <translation>Ein Gitter von {spacing:g} m über die Punkte von '{name}' hätte mehr als 400 Millionen Zellen; geben Sie eine größere Gitterweite an.</translation>
        </message>
        <message>
            <source>The filter input '{path}' does not exist or is not a file.</source>
            <extracomment>algorithms/filtering/surface_input.py:355</extracomment>
            <translation>Die Filtereingabe '{path}' existiert nicht oder ist keine Datei.</translation>
        </message>
        <message>
            <source>The filter input has no CRS and neither has the project; give the CRS of the input (e.g. --crs EPSG:25832) so the edits can be placed.</source>
            <extracomment>algorithms/filtering/surface_input.py:411</extracomment>
            <translation>Weder die Filtereingabe noch das Projekt hat ein KBS; geben Sie das KBS der Eingabe an (z. B. --crs EPSG:25832), damit die Bearbeitungen platziert werden können.</translation>
        </message>
        <message>
            <source>Unknown CRS '{crs}': give an EPSG code (e.g. EPSG:25832), WKT or a PROJ string ({error}).</source>
            <extracomment>algorithms/filtering/surface_input.py:162</extracomment>
            <translation>Unbekanntes KBS '{crs}': Geben Sie einen EPSG-Code (z. B. EPSG:25832), WKT oder eine PROJ-Zeichenkette an ({error}).</translation>
        </message>
        <message>
            <source>Cannot read '{name}' as a DSM raster or a points file: {error}</source>
            <extracomment>algorithms/filtering/surface_input.py:193</extracomment>
            <translation>'{name}' kann weder als DOM-Raster noch als Punktdatei gelesen werden: {error}</translation>
        </message>
        <message>
            <source>Cannot read the LAS/LAZ file '{name}': {error}</source>
            <extracomment>algorithms/filtering/surface_input.py:218</extracomment>
            <translation>Die LAS/LAZ-Datei '{name}' kann nicht gelesen werden: {error}</translation>
        </message>
        <message>
            <source>The DSM '{name}' is rotated or not north-up; warp it to a north-up grid first (e.g. gdalwarp).</source>
            <extracomment>algorithms/filtering/surface_input.py:180</extracomment>
            <translation>Das DOM '{name}' ist gedreht oder nicht nordausgerichtet; transformieren Sie es zuerst auf ein nordausgerichtetes Gitter (z. B. gdalwarp).</translation>
        </message>
        <message>
            <source>The DSM '{name}' has non-square cells ({width:g} × {height:g}); resample it to square cells first.</source>
            <extracomment>algorithms/filtering/surface_input.py:183</extracomment>
            <translation>Das DOM '{name}' hat nicht quadratische Zellen ({width:g} × {height:g}); tasten Sie es zuerst auf quadratische Zellen um.</translation>
        </message>
        <message>
            <source>Cannot read '{name}' as points: {error}</source>
            <extracomment>algorithms/filtering/surface_input.py:293</extracomment>
            <translation>'{name}' kann nicht als Punkte gelesen werden: {error}</translation>
        </message>
        <message>
            <source>Unknown keypoint detector '{value}'; use auto, {options}.</source>
            <extracomment>algorithms/georef/keypoints.py:127; algorithms/georef/pipeline.py:205</extracomment>
            <translation>Unbekannter Merkmalsdetektor '{value}'; verwenden Sie auto, {options}.</translation>
        </message>
        <message>
            <source>The image has no valid pixels.</source>
            <extracomment>algorithms/georef/keypoints.py:84; algorithms/georef/regions.py:278</extracomment>
            <translation>Das Bild hat keine gültigen Pixel.</translation>
        </message>
        <message>
            <source>Thresholds must be positive grey-value differences, e.g. 5,6,7,8.</source>
            <extracomment>algorithms/georef/pipeline.py:110</extracomment>
            <translation>Die Schwellen müssen positive Grauwertdifferenzen sein, z. B. 5,6,7,8.</translation>
        </message>
        <message>
            <source>The area-based search needs a polygon layer as reference, not a raster; use search = objects or auto.</source>
            <extracomment>algorithms/georef/pipeline.py:258</extracomment>
            <translation>Die flächenbasierte Suche braucht einen Polygonlayer als Referenz, kein Raster; verwenden Sie search = objects oder auto.</translation>
        </message>
        <message>
            <source>The keypoint search needs a georeferenced raster as reference, not a polygon layer; use search = objects, area or auto.</source>
            <extracomment>algorithms/georef/pipeline.py:261</extracomment>
            <translation>Die Merkmalspunktsuche braucht ein georeferenziertes Raster als Referenz, keinen Polygonlayer; verwenden Sie search = objects, area oder auto.</translation>
        </message>
        <message>
            <source>Georeferencing failed: {why} ({detail}). Check that image and reference show the same objects completely (class field/value), try other thresholds or a larger relative difference.</source>
            <extracomment>algorithms/georef/pipeline.py:790</extracomment>
            <translation>Die Georeferenzierung ist fehlgeschlagen: {why} ({detail}). Prüfen Sie, ob Bild und Referenz dieselben Objekte vollständig zeigen (Klassenfeld/-wert), versuchen Sie andere Schwellen oder eine größere relative Differenz.</translation>
        </message>
        <message>
            <source>The output folder '{path}' holds files PhotoDEM did not write; choose an empty or new folder.</source>
            <extracomment>algorithms/georef/pipeline.py:828</extracomment>
            <translation>Der Ausgabeordner '{path}' enthält Dateien, die PhotoDEM nicht geschrieben hat; wählen Sie einen leeren oder neuen Ordner.</translation>
        </message>
        <message>
            <source>Unknown transform '{value}'; use affine, projective or poly2.</source>
            <extracomment>algorithms/georef/pipeline.py:199</extracomment>
            <translation>Unbekannte Transformation '{value}'; verwenden Sie affine, projective oder poly2.</translation>
        </message>
        <message>
            <source>Unknown search '{value}'; use {options}.</source>
            <extracomment>algorithms/georef/pipeline.py:202</extracomment>
            <translation>Unbekannte Suche '{value}'; verwenden Sie {options}.</translation>
        </message>
        <message>
            <source>Unknown objects '{value}'; use {options}.</source>
            <extracomment>algorithms/georef/pipeline.py:208</extracomment>
            <translation>Unbekannte Objekte '{value}'; verwenden Sie {options}.</translation>
        </message>
        <message>
            <source>The time limit must be ≥ 0 s (0: none), not {value}.</source>
            <extracomment>algorithms/georef/pipeline.py:211</extracomment>
            <translation>Das Zeitlimit muss ≥ 0 s sein (0: keines), nicht {value}.</translation>
        </message>
        <message>
            <source>Thresholds '{text}': give numbers separated by commas, e.g. 5,6,7,8.</source>
            <extracomment>algorithms/georef/pipeline.py:105</extracomment>
            <translation>Schwellen '{text}': Geben Sie durch Kommas getrennte Zahlen an, z. B. 5,6,7,8.</translation>
        </message>
        <message>
            <source>Georeferencing failed: the {stage} stage's result is not verified: {why} (RMSE {rmse:.2f} px of {points} control points; {evidence}). No result is better than a wrong one: check that image and reference show the same area, or write the result marked unverified.</source>
            <extracomment>algorithms/georef/pipeline.py:329</extracomment>
            <translation>Die Georeferenzierung ist fehlgeschlagen: Das Ergebnis der Stufe {stage} ist nicht bestätigt: {why} (RMSE {rmse:.2f} px aus {points} Passpunkten; {evidence}). Kein Ergebnis ist besser als ein falsches: Prüfen Sie, ob Bild und Referenz dasselbe Gebiet zeigen, oder schreiben Sie das Ergebnis als unbestätigt markiert.</translation>
        </message>
        <message>
            <source>{error} Before it, the keypoint stage found no result: {why} ({detail}).</source>
            <extracomment>algorithms/georef/pipeline.py:395</extracomment>
            <translation>{error} Zuvor hat die Merkmalspunktstufe kein Ergebnis gefunden: {why} ({detail}).</translation>
        </message>
        <message>
            <source>Reference layer '{path}' not found.</source>
            <extracomment>algorithms/georef/reference_layer.py:120</extracomment>
            <translation>Referenzlayer '{path}' nicht gefunden.</translation>
        </message>
        <message>
            <source>No polygons in the reference layer '{name}' ({count} features read); check the class field and value.</source>
            <extracomment>algorithms/georef/reference_layer.py:155</extracomment>
            <translation>Keine Polygone im Referenzlayer '{name}' ({count} Objekte gelesen); prüfen Sie Klassenfeld und -wert.</translation>
        </message>
        <message>
            <source>The reference layer '{name}' has no CRS; assign one in QGIS first.</source>
            <extracomment>algorithms/georef/reference_layer.py:159</extracomment>
            <translation>Der Referenzlayer '{name}' hat kein KBS; weisen Sie ihm zuerst in QGIS eines zu.</translation>
        </message>
        <message>
            <source>The reference raster '{name}' is in a geographic CRS; reproject it to a projected CRS first.</source>
            <extracomment>algorithms/georef/reference_layer.py:223</extracomment>
            <translation>Das Referenzraster '{name}' liegt in einem geographischen KBS; projizieren Sie es zuerst in ein projiziertes KBS um.</translation>
        </message>
        <message>
            <source>Cannot read the reference layer '{path}': {error}</source>
            <extracomment>algorithms/georef/reference_layer.py:124</extracomment>
            <translation>Der Referenzlayer '{path}' kann nicht gelesen werden: {error}</translation>
        </message>
        <message>
            <source>The reference layer '{name}' has no attribute '{field}'; its attributes are: {fields}.</source>
            <extracomment>algorithms/georef/reference_layer.py:129</extracomment>
            <translation>Der Referenzlayer '{name}' hat kein Attribut '{field}'; seine Attribute sind: {fields}.</translation>
        </message>
        <message>
            <source>No polygons with {field} = {value} in the reference layer '{name}' ({count} features read); check the class field and value.</source>
            <extracomment>algorithms/georef/reference_layer.py:151</extracomment>
            <translation>Keine Polygone mit {field} = {value} im Referenzlayer '{name}' ({count} Objekte gelesen); prüfen Sie Klassenfeld und -wert.</translation>
        </message>
        <message>
            <source>The reference raster '{name}' has no georeference; a raster reference must be georeferenced (an orthophoto).</source>
            <extracomment>algorithms/georef/reference_layer.py:218</extracomment>
            <translation>Das Referenzraster '{name}' hat keine Georeferenz; eine Rasterreferenz muss georeferenziert sein (ein Orthofoto).</translation>
        </message>
        <message>
            <source>Unknown scan start corner '{value}'; use one of {options}.</source>
            <extracomment>algorithms/georef/regions.py:49</extracomment>
            <translation>Unbekannte Startecke '{value}'; verwenden Sie eine von {options}.</translation>
        </message>
        <message>
            <source>Image '{path}' not found.</source>
            <extracomment>algorithms/georef/regions.py:427</extracomment>
            <translation>Bild '{path}' nicht gefunden.</translation>
        </message>
        <message>
            <source>Cannot read image '{path}': {error}</source>
            <extracomment>algorithms/georef/regions.py:442</extracomment>
            <translation>Das Bild '{path}' kann nicht gelesen werden: {error}</translation>
        </message>
        <message>
            <source>Band {band} does not exist: '{name}' has {count} band(s).</source>
            <extracomment>algorithms/georef/regions.py:431</extracomment>
            <translation>Kanal {band} existiert nicht: '{name}' hat {count} Kanal/Kanäle.</translation>
        </message>
        <message>
            <source>The check-point file '{path}' does not exist.</source>
            <extracomment>algorithms/georef/review.py:295</extracomment>
            <translation>Die Kontrollpunktdatei '{path}' existiert nicht.</translation>
        </message>
        <message>
            <source>The check-point file '{name}' holds no check points.</source>
            <extracomment>algorithms/georef/review.py:299</extracomment>
            <translation>Die Kontrollpunktdatei '{name}' enthält keine Kontrollpunkte.</translation>
        </message>
        <message>
            <source>The check-point file '{name}' has a header but no check points.</source>
            <extracomment>algorithms/georef/review.py:306</extracomment>
            <translation>Die Kontrollpunktdatei '{name}' hat eine Kopfzeile, aber keine Kontrollpunkte.</translation>
        </message>
        <message>
            <source>'{name}' has no header line; the first line must name the columns, e.g. col,row,x,y or pixel,line,mapX,mapY.</source>
            <extracomment>algorithms/georef/review.py:321</extracomment>
            <translation>'{name}' hat keine Kopfzeile; die erste Zeile muss die Spalten benennen, z. B. col,row,x,y oder pixel,line,mapX,mapY.</translation>
        </message>
        <message>
            <source>The header of '{name}' lacks {missing} (found: {found}); name the columns col,row,x,y or pixel,line,mapX,mapY.</source>
            <extracomment>algorithms/georef/review.py:330</extracomment>
            <translation>In der Kopfzeile von '{name}' fehlt {missing} (gefunden: {found}); benennen Sie die Spalten col,row,x,y oder pixel,line,mapX,mapY.</translation>
        </message>
        <message>
            <source>'{name}': the line column mixes positive and negative values; a QGIS .points file has negative lines, a GDAL list positive ones.</source>
            <extracomment>algorithms/georef/review.py:367</extracomment>
            <translation>'{name}': Die Zeilenspalte mischt positive und negative Werte; eine .points-Datei von QGIS hat negative Zeilen, eine GDAL-Liste positive.</translation>
        </message>
        <message>
            <source>'{name}' is in another CRS than the georeferencing result; export the check points in the result's CRS.</source>
            <extracomment>algorithms/georef/review.py:381</extracomment>
            <translation>'{name}' liegt in einem anderen KBS als das Ergebnis der Georeferenzierung; exportieren Sie die Kontrollpunkte im KBS des Ergebnisses.</translation>
        </message>
        <message>
            <source>None of the {count} check points in '{name}' lies in the image ({width} × {height} pixels); col,row count pixel centres from 0, pixel,line are QGIS .points coordinates.</source>
            <extracomment>algorithms/georef/review.py:394</extracomment>
            <translation>Keiner der {count} Kontrollpunkte in '{name}' liegt im Bild ({width} × {height} Pixel); col,row zählen Pixelmitten ab 0, pixel,line sind Koordinaten einer .points-Datei von QGIS.</translation>
        </message>
        <message>
            <source>'{folder}' holds no georeferencing result (report.json and a .points file); choose the output folder of 'Georeference image against polygons'.</source>
            <extracomment>algorithms/georef/review.py:424</extracomment>
            <translation>'{folder}' enthält kein Ergebnis einer Georeferenzierung (report.json und eine .points-Datei); wählen Sie den Ausgabeordner von 'Bild an Polygonen georeferenzieren'.</translation>
        </message>
        <message>
            <source>'{name}' is missing in '{folder}'; the review resamples that copy of the image. Run the georeferencing again.</source>
            <extracomment>algorithms/georef/review.py:474</extracomment>
            <translation>'{name}' fehlt in '{folder}'; die Prüfung tastet diese Kopie des Bildes um. Führen Sie die Georeferenzierung erneut aus.</translation>
        </message>
        <message>
            <source>A control point needs four finite numbers: column, row, X, Y.</source>
            <extracomment>algorithms/georef/review.py:148</extracomment>
            <translation>Ein Passpunkt braucht vier endliche Zahlen: Spalte, Zeile, X, Y.</translation>
        </message>
        <message>
            <source>Unknown transform '{value}'; use {options}.</source>
            <extracomment>algorithms/georef/review.py:169</extracomment>
            <translation>Unbekannte Transformation '{value}'; verwenden Sie {options}.</translation>
        </message>
        <message>
            <source>The {kind} transform needs at least {need} active control points; {count} are switched on.</source>
            <extracomment>algorithms/georef/review.py:174</extracomment>
            <translation>Die Transformation {kind} braucht mindestens {need} aktive Passpunkte; eingeschaltet sind {count}.</translation>
        </message>
        <message>
            <source>Cannot read the georeferencing result in '{folder}': {error}</source>
            <extracomment>algorithms/georef/review.py:436</extracomment>
            <translation>Das Ergebnis der Georeferenzierung in '{folder}' kann nicht gelesen werden: {error}</translation>
        </message>
        <message>
            <source>The active control points do not determine a {kind} transform ({error}); switch on points spread over the image.</source>
            <extracomment>algorithms/georef/review.py:181</extracomment>
            <translation>Die aktiven Passpunkte bestimmen keine Transformation {kind} ({error}); schalten Sie über das Bild verteilte Punkte ein.</translation>
        </message>
        <message>
            <source>'{name}' line {number}: {column} '{token}' is not a number.</source>
            <extracomment>algorithms/georef/review.py:352</extracomment>
            <translation>'{name}' Zeile {number}: {column} '{token}' ist keine Zahl.</translation>
        </message>
        <message>
            <source>The {what} name '{name}' is not valid UTF-8 text; GDAL cannot open it. Rename the file (or its folder) with UTF-8 characters only.</source>
            <extracomment>algorithms/input_errors.py:94</extracomment>
            <translation>Der Name '{name}' ({what}) ist kein gültiger UTF-8-Text; GDAL kann die Datei nicht öffnen. Benennen Sie die Datei (oder ihren Ordner) nur mit UTF-8-Zeichen um.</translation>
        </message>
        <message>
            <source>Cannot use {shown}: {reason}.</source>
            <extracomment>algorithms/input_errors.py:182</extracomment>
            <translation>Zugriff auf {shown} nicht möglich: {reason}.</translation>
        </message>
        <message>
            <source>An input file cannot be read ({detail}). Check the file it names (replace a truncated or damaged copy).</source>
            <extracomment>algorithms/input_errors.py:188</extracomment>
            <translation>Eine Eingabedatei kann nicht gelesen werden ({detail}). Prüfen Sie die genannte Datei (ersetzen Sie eine abgeschnittene oder beschädigte Kopie).</translation>
        </message>
        <message>
            <source>file</source>
            <extracomment>algorithms/input_errors.py:81; algorithms/processing/batch.py:140</extracomment>
            <translation>Datei</translation>
        </message>
        <message>
            <source>raster</source>
            <extracomment>algorithms/input_errors.py:81</extracomment>
            <translation>Raster</translation>
        </message>
        <message>
            <source>image</source>
            <extracomment>algorithms/input_errors.py:81; algorithms/processing/batch.py:140; algorithms/project/model.py:77</extracomment>
            <translation>Bild</translation>
        </message>
        <message>
            <source>surface</source>
            <extracomment>algorithms/input_errors.py:81</extracomment>
            <translation>Oberfläche</translation>
        </message>
        <message>
            <source>output</source>
            <extracomment>algorithms/input_errors.py:81</extracomment>
            <translation>Ausgabe</translation>
        </message>
        <message>
            <source>vector file</source>
            <extracomment>algorithms/input_errors.py:82</extracomment>
            <translation>Vektordatei</translation>
        </message>
        <message>
            <source>text file</source>
            <extracomment>algorithms/input_errors.py:82</extracomment>
            <translation>Textdatei</translation>
        </message>
        <message>
            <source>GeoPackage</source>
            <extracomment>algorithms/input_errors.py:82</extracomment>
            <translation>GeoPackage</translation>
        </message>
        <message>
            <source>project file</source>
            <extracomment>algorithms/input_errors.py:82</extracomment>
            <translation>Projektdatei</translation>
        </message>
        <message>
            <source>seamline file</source>
            <extracomment>algorithms/input_errors.py:83</extracomment>
            <translation>Schnittliniendatei</translation>
        </message>
        <message>
            <source>A file name that is not valid UTF-8 text could not be written into a report; rename the file with UTF-8 characters only.</source>
            <extracomment>algorithms/input_errors.py:173</extracomment>
            <translation>Ein Dateiname, der kein gültiger UTF-8-Text ist, konnte nicht in einen Bericht geschrieben werden; benennen Sie die Datei nur mit UTF-8-Zeichen um.</translation>
        </message>
        <message>
            <source>'{path}'</source>
            <extracomment>algorithms/input_errors.py:179</extracomment>
            <translation>'{path}'</translation>
        </message>
        <message>
            <source>the {what}</source>
            <extracomment>algorithms/input_errors.py:180</extracomment>
            <translation>die Eingabe ({what})</translation>
        </message>
        <message>
            <source>'{path}' is not a readable {what} ({detail}).</source>
            <extracomment>algorithms/input_errors.py:186</extracomment>
            <translation>'{path}' kann nicht als {what} gelesen werden ({detail}).</translation>
        </message>
        <message>
            <source>'{path}' is an empty raster (no band or no cells).</source>
            <extracomment>algorithms/input_errors.py:285</extracomment>
            <translation>'{path}' ist ein leeres Raster (kein Kanal oder keine Zellen).</translation>
        </message>
        <message>
            <source>Parameter '{name}': {error}</source>
            <extracomment>algorithms/input_errors.py:333; algorithms/input_errors.py:347</extracomment>
            <translation>Parameter '{name}': {error}</translation>
        </message>
        <message>
            <source>The disparity range {min_d}…{max_d} px holds no possible disparity of these images (widths {left_width} and {right_width} px allow {low}…{high}); change {parameter}.</source>
            <extracomment>algorithms/matching/dense.py:374</extracomment>
            <translation>Der Disparitätsbereich {min_d}…{max_d} px enthält keine mögliche Disparität dieser Bilder (Breiten {left_width} und {right_width} px erlauben {low}…{high}); ändern Sie {parameter}.</translation>
        </message>
        <message>
            <source>The disparity range is empty (min {min_d} &gt; max {max_d}); give min_disparity ≤ max_disparity.</source>
            <extracomment>algorithms/matching/dense.py:484</extracomment>
            <translation>Der Disparitätsbereich ist leer (min {min_d} &gt; max {max_d}); geben Sie min_disparity ≤ max_disparity an.</translation>
        </message>
        <message>
            <source>max_height ({z_max}) must be larger than min_height ({z_min}).</source>
            <extracomment>algorithms/matching/model_setup.py:147</extracomment>
            <translation>max_height ({z_max}) muss größer als min_height ({z_min}) sein.</translation>
        </message>
        <message>
            <source>max_height ({z_max:.1f} m) reaches the cameras ({z_cam:.1f} m); give a lower max_height.</source>
            <extracomment>algorithms/matching/model_setup.py:150</extracomment>
            <translation>max_height ({z_max:.1f} m) reicht bis zu den Kameras ({z_cam:.1f} m); geben Sie ein niedrigeres max_height an.</translation>
        </message>
        <message>
            <source>The images {left} and {right} of model '{model}' do not overlap; check the model or the orientations.</source>
            <extracomment>algorithms/matching/model_setup.py:210</extracomment>
            <translation>Die Bilder {left} und {right} des Modells '{model}' überlappen sich nicht; prüfen Sie das Modell oder die Orientierungen.</translation>
        </message>
        <message>
            <source>The spacing must be positive, got {spacing}.</source>
            <extracomment>algorithms/matching/model_setup.py:218</extracomment>
            <translation>Die Gitterweite muss positiv sein, angegeben: {spacing}.</translation>
        </message>
        <message>
            <source>Model '{model}': the height range {z_min:.1f}…{z_max:.1f} m gives no disparity; check min_height/max_height.</source>
            <extracomment>algorithms/matching/model_setup.py:222</extracomment>
            <translation>Modell '{model}': Der Höhenbereich {z_min:.1f}…{z_max:.1f} m ergibt keine Disparität; prüfen Sie min_height/max_height.</translation>
        </message>
        <message>
            <source>The boundaries of edits.gpkg do not touch model '{model}'.</source>
            <extracomment>algorithms/matching/model_setup.py:238</extracomment>
            <translation>Die Begrenzungen in edits.gpkg berühren das Modell '{model}' nicht.</translation>
        </message>
        <message>
            <source>{label} exists and is {what}; only an earlier '{algorithm}' result is replaced. Choose another file name.</source>
            <extracomment>algorithms/output_policy.py:315</extracomment>
            <translation>{label} existiert bereits und ist {what}; ersetzt wird nur ein früheres Ergebnis von '{algorithm}'. Wählen Sie einen anderen Dateinamen.</translation>
        </message>
        <message>
            <source>{what} leads to '{path}', outside '{folder}'; rename it (names may not contain '/', '\' or '..').</source>
            <extracomment>algorithms/output_policy.py:95</extracomment>
            <translation>{what} führt zu '{path}', außerhalb von '{folder}'; benennen Sie es um (Namen dürfen weder '/', '\' noch '..' enthalten).</translation>
        </message>
        <message>
            <source>Parameter '{name}': the output '{path}'</source>
            <extracomment>algorithms/output_policy.py:243</extracomment>
            <translation>Parameter '{name}': Die Ausgabe '{path}'</translation>
        </message>
        <message>
            <source>{label} is a folder, but a file is expected; give a file name.</source>
            <extracomment>algorithms/output_policy.py:271</extracomment>
            <translation>{label} ist ein Ordner, erwartet wird aber eine Datei; geben Sie einen Dateinamen an.</translation>
        </message>
        <message>
            <source>{label} is a file, but a folder is expected; give a folder name.</source>
            <extracomment>algorithms/output_policy.py:274</extracomment>
            <translation>{label} ist eine Datei, erwartet wird aber ein Ordner; geben Sie einen Ordnernamen an.</translation>
        </message>
        <message>
            <source>{label} is or contains a PhotoDEM project; choose a folder outside it (e.g. below its products/ folder).</source>
            <extracomment>algorithms/output_policy.py:280</extracomment>
            <translation>{label} ist oder enthält ein PhotoDEM-Projekt; wählen Sie einen Ordner außerhalb davon (z. B. unterhalb seines Ordners products/).</translation>
        </message>
        <message>
            <source>{label} holds {what}; only an earlier '{algorithm}' result is replaced. Choose an empty or new folder.</source>
            <extracomment>algorithms/output_policy.py:300</extracomment>
            <translation>{label} enthält {what}; ersetzt wird nur ein früheres Ergebnis von '{algorithm}'. Wählen Sie einen leeren oder neuen Ordner.</translation>
        </message>
        <message>
            <source>{label} exists and does not belong to an earlier '{algorithm}' result '{owner}'; move it or choose another output name.</source>
            <extracomment>algorithms/output_policy.py:307</extracomment>
            <translation>{label} existiert bereits und gehört nicht zu einem früheren Ergebnis '{owner}' von '{algorithm}'; verschieben Sie die Datei oder wählen Sie einen anderen Ausgabenamen.</translation>
        </message>
        <message>
            <source>a product of '{other}'</source>
            <extracomment>algorithms/output_policy.py:298; algorithms/output_policy.py:313; algorithms/raster/io.py:236</extracomment>
            <translation>ein Produkt von '{other}'</translation>
        </message>
        <message>
            <source>a file PhotoDEM did not write</source>
            <extracomment>algorithms/output_policy.py:314</extracomment>
            <translation>eine Datei, die nicht von PhotoDEM stammt</translation>
        </message>
        <message>
            <source>{label} is the working, home or root folder; name a new folder or file inside it.</source>
            <extracomment>algorithms/output_policy.py:246</extracomment>
            <translation>{label} ist der Arbeits-, Benutzer- oder Stammordner; geben Sie darin einen neuen Ordner oder eine neue Datei an.</translation>
        </message>
        <message>
            <source>{label} is part of the project '{root}' ({part}); write products below its products/ folder.</source>
            <extracomment>algorithms/output_policy.py:286</extracomment>
            <translation>{label} gehört zum Projekt '{root}' ({part}); schreiben Sie Produkte unterhalb seines Ordners products/.</translation>
        </message>
        <message>
            <source>files PhotoDEM did not write</source>
            <extracomment>algorithms/output_policy.py:299; algorithms/raster/io.py:237</extracomment>
            <translation>Dateien, die nicht von PhotoDEM stammen</translation>
        </message>
        <message>
            <source>{label} is or contains the input '{input}'; PhotoDEM never overwrites its inputs. Choose another output.</source>
            <extracomment>algorithms/output_policy.py:253</extracomment>
            <translation>{label} ist oder enthält die Eingabe '{input}'; PhotoDEM überschreibt niemals seine Eingaben. Wählen Sie eine andere Ausgabe.</translation>
        </message>
        <message>
            <source>{label} lies below '{parent}', which is a file; choose a path in a folder.</source>
            <extracomment>algorithms/output_policy.py:264</extracomment>
            <translation>{label} liegt unterhalb von '{parent}', das eine Datei ist; wählen Sie einen Pfad in einem Ordner.</translation>
        </message>
        <message>
            <source>model</source>
            <extracomment>algorithms/processing/batch.py:140</extracomment>
            <translation>Modell</translation>
        </message>
        <message>
            <source>models</source>
            <extracomment>algorithms/processing/batch.py:141</extracomment>
            <translation>Modelle</translation>
        </message>
        <message>
            <source>images</source>
            <extracomment>algorithms/processing/batch.py:141</extracomment>
            <translation>Bilder</translation>
        </message>
        <message>
            <source>files</source>
            <extracomment>algorithms/processing/batch.py:141</extracomment>
            <translation>Dateien</translation>
        </message>
        <message>
            <source>step {number}</source>
            <extracomment>algorithms/processing/batch.py:340</extracomment>
            <translation>Schritt {number}</translation>
        </message>
        <message>
            <source>Batch file '{path}' does not exist.</source>
            <extracomment>algorithms/processing/batch.py:227</extracomment>
            <translation>Die Batch-Datei '{path}' existiert nicht.</translation>
        </message>
        <message>
            <source>Batch file: unknown table(s) {tables}; expected [batch] and [[steps]].</source>
            <extracomment>algorithms/processing/batch.py:249</extracomment>
            <translation>Batch-Datei: unbekannte Tabelle(n) {tables}; erwartet werden [batch] und [[steps]].</translation>
        </message>
        <message>
            <source>Batch file: batch must be a table: write [batch] on a line of its own with project = …, workers = …, output = … below it.</source>
            <extracomment>algorithms/processing/batch.py:253</extracomment>
            <translation>Batch-Datei: batch muss eine Tabelle sein: Schreiben Sie [batch] in eine eigene Zeile und darunter project = …, workers = …, output = ….</translation>
        </message>
        <message>
            <source>Batch file: workers = {value} in [batch] must be a whole number ≥ 1.</source>
            <extracomment>algorithms/processing/batch.py:268</extracomment>
            <translation>Batch-Datei: workers = {value} in [batch] muss eine ganze Zahl ≥ 1 sein.</translation>
        </message>
        <message>
            <source>the run folder</source>
            <extracomment>algorithms/processing/batch.py:281</extracomment>
            <translation>der Laufordner</translation>
        </message>
        <message>
            <source>Batch file: write each step as [[steps]] (two brackets), not [steps].</source>
            <extracomment>algorithms/processing/batch.py:286</extracomment>
            <translation>Batch-Datei: Schreiben Sie jeden Schritt als [[steps]] (zwei Klammern), nicht als [steps].</translation>
        </message>
        <message>
            <source>Batch file: no [[steps]]; add at least one step with algorithm = "id".</source>
            <extracomment>algorithms/processing/batch.py:289</extracomment>
            <translation>Batch-Datei: kein [[steps]]; fügen Sie mindestens einen Schritt mit algorithm = "id" hinzu.</translation>
        </message>
        <message>
            <source>Batch file: {key} = {value} in {where} must be a string in quotes, e.g. {key} = "…".</source>
            <extracomment>algorithms/processing/batch.py:317</extracomment>
            <translation>Batch-Datei: {key} = {value} in {where} muss eine Zeichenkette in Anführungszeichen sein, z. B. {key} = "…".</translation>
        </message>
        <message>
            <source>Batch file: unknown key(s) {keys} in {where}; allowed are {allowed}.</source>
            <extracomment>algorithms/processing/batch.py:325</extracomment>
            <translation>Batch-Datei: unbekannte(r) Schlüssel {keys} in {where}; erlaubt sind {allowed}.</translation>
        </message>
        <message>
            <source>Batch file: step {number} needs algorithm = "id".</source>
            <extracomment>algorithms/processing/batch.py:343</extracomment>
            <translation>Batch-Datei: Schritt {number} braucht algorithm = "id".</translation>
        </message>
        <message>
            <source>Batch file: step name {name} may hold only letters, digits, '_', '-' and '.' (it names the log files).</source>
            <extracomment>algorithms/processing/batch.py:349</extracomment>
            <translation>Batch-Datei: Der Schrittname {name} darf nur Buchstaben, Ziffern, '_', '-' und '.' enthalten (er benennt die Protokolldateien).</translation>
        </message>
        <message>
            <source>Batch file: two steps are named {name}; give them distinct names.</source>
            <extracomment>algorithms/processing/batch.py:352</extracomment>
            <translation>Batch-Datei: Zwei Schritte heißen {name}; geben Sie ihnen verschiedene Namen.</translation>
        </message>
        <message>
            <source>Batch file: params of step '{step}' must be a table.</source>
            <extracomment>algorithms/processing/batch.py:357</extracomment>
            <translation>Batch-Datei: params des Schritts '{step}' muss eine Tabelle sein.</translation>
        </message>
        <message>
            <source>Batch file: step '{step}' ({algorithm}): unknown parameter(s) {unknown}; known are {known}.</source>
            <extracomment>algorithms/processing/batch.py:448</extracomment>
            <translation>Batch-Datei: Schritt '{step}' ({algorithm}): unbekannte(r) Parameter {unknown}; bekannt sind {known}.</translation>
        </message>
        <message>
            <source>Batch file: step '{step}' needs files = ["&lt;pattern or path&gt;", …] (the values of its parameter '{parameter}').</source>
            <extracomment>algorithms/processing/batch.py:559</extracomment>
            <translation>Batch-Datei: Schritt '{step}' braucht files = ["&lt;Muster oder Pfad&gt;", …] (die Werte seines Parameters '{parameter}').</translation>
        </message>
        <message>
            <source>Batch file: step '{step}': files must be a pattern or a list of patterns/paths.</source>
            <extracomment>algorithms/processing/batch.py:564</extracomment>
            <translation>Batch-Datei: Schritt '{step}': files muss ein Muster oder eine Liste von Mustern/Pfaden sein.</translation>
        </message>
        <message>
            <source>Batch file: step '{step}' uses {{{key}}}, but it does not run per {key}.</source>
            <extracomment>algorithms/processing/batch.py:614</extracomment>
            <translation>Batch-Datei: Schritt '{step}' verwendet {{{key}}}, läuft aber nicht einzeln für jedes '{key}'.</translation>
        </message>
        <message>
            <source>Cannot read batch file '{path}': {error}</source>
            <extracomment>algorithms/processing/batch.py:231</extracomment>
            <translation>Die Batch-Datei '{path}' kann nicht gelesen werden: {error}</translation>
        </message>
        <message>
            <source>Batch file: step {number} is not a table.</source>
            <extracomment>algorithms/processing/batch.py:296</extracomment>
            <translation>Batch-Datei: Schritt {number} ist keine Tabelle.</translation>
        </message>
        <message>
            <source>Batch file: step '{step}' sets {key}, but {algorithm} iterates over {items}.</source>
            <extracomment>algorithms/processing/batch.py:380</extracomment>
            <translation>Batch-Datei: Schritt '{step}' setzt {key}, aber {algorithm} läuft über {items}.</translation>
        </message>
        <message>
            <source>step '{step}' ({algorithm})</source>
            <extracomment>algorithms/processing/batch.py:424</extracomment>
            <translation>Schritt '{step}' ({algorithm})</translation>
        </message>
        <message>
            <source>step '{step}' ({algorithm}), {kind} '{label}'</source>
            <extracomment>algorithms/processing/batch.py:426</extracomment>
            <translation>Schritt '{step}' ({algorithm}), {kind} '{label}'</translation>
        </message>
        <message>
            <source>Batch file: {named} (where the batch writes its logs): {error}</source>
            <extracomment>algorithms/processing/batch.py:490</extracomment>
            <translation>Batch-Datei: {named} (dort schreibt der Batch seine Protokolle): {error}</translation>
        </message>
        <message>
            <source>Batch file: {where}: {error}</source>
            <extracomment>algorithms/processing/batch.py:518</extracomment>
            <translation>Batch-Datei: {where}: {error}</translation>
        </message>
        <message>
            <source>Batch file: step '{step}': '{first}' and '{second}' have the same name; {{file}} must name one file (rename one).</source>
            <extracomment>algorithms/processing/batch.py:587</extracomment>
            <translation>Batch-Datei: Schritt '{step}': '{first}' und '{second}' haben denselben Namen; {{file}} muss eine einzige Datei bezeichnen (benennen Sie eine um).</translation>
        </message>
        <message>
            <source>Batch file: step '{step}' uses {{project}}, but the batch has no project (set project = "…" in [batch]).</source>
            <extracomment>algorithms/processing/batch.py:612</extracomment>
            <translation>Batch-Datei: Schritt '{step}' verwendet {{project}}, aber der Batch hat kein Projekt (setzen Sie project = "…" in [batch]).</translation>
        </message>
        <message>
            <source>Batch file: step '{step}' ({algorithm}) needs a project; set project = "&lt;project folder&gt;" in [batch].</source>
            <extracomment>algorithms/processing/batch.py:362</extracomment>
            <translation>Batch-Datei: Schritt '{step}' ({algorithm}) braucht ein Projekt; setzen Sie project = "&lt;Projektordner&gt;" in [batch].</translation>
        </message>
        <message>
            <source>Batch file: step '{step}' sets {key}, but {algorithm} does not iterate.</source>
            <extracomment>algorithms/processing/batch.py:378</extracomment>
            <translation>Batch-Datei: Schritt '{step}' setzt {key}, aber {algorithm} läuft über nichts.</translation>
        </message>
        <message>
            <source>Batch file: step '{step}' runs over the project's {items}; set project = "&lt;project folder&gt;" in [batch].</source>
            <extracomment>algorithms/processing/batch.py:388</extracomment>
            <translation>Batch-Datei: Schritt '{step}' läuft über die {items} des Projekts; setzen Sie project = "&lt;Projektordner&gt;" in [batch].</translation>
        </message>
        <message>
            <source>Batch file: step '{step}': the project has no {items}.</source>
            <extracomment>algorithms/processing/batch.py:409</extracomment>
            <translation>Batch-Datei: Schritt '{step}': Das Projekt hat keine {items}.</translation>
        </message>
        <message>
            <source>Batch file: step '{step}' ({algorithm}): {error}</source>
            <extracomment>algorithms/processing/batch.py:456</extracomment>
            <translation>Batch-Datei: Schritt '{step}' ({algorithm}): {error}</translation>
        </message>
        <message>
            <source>Batch file: step '{step}': no file matches '{pattern}'.</source>
            <extracomment>algorithms/processing/batch.py:575</extracomment>
            <translation>Batch-Datei: Schritt '{step}': Keine Datei passt zu '{pattern}'.</translation>
        </message>
        <message>
            <source>Batch file: step '{step}': file '{pattern}' does not exist.</source>
            <extracomment>algorithms/processing/batch.py:581</extracomment>
            <translation>Batch-Datei: Schritt '{step}': Die Datei '{pattern}' existiert nicht.</translation>
        </message>
        <message>
            <source>Batch file: step '{step}': {items} must be "all" or a list of names.</source>
            <extracomment>algorithms/processing/batch.py:406</extracomment>
            <translation>Batch-Datei: Schritt '{step}': {items} muss "all" oder eine Liste von Namen sein.</translation>
        </message>
        <message>
            <source>Batch file: step '{step}': {kind}(s) {missing} not in the project; it has {available}.</source>
            <extracomment>algorithms/processing/batch.py:399</extracomment>
            <translation>Batch-Datei: Schritt '{step}': {missing} ({kind}) nicht im Projekt; vorhanden: {available}.</translation>
        </message>
        <message>
            <source>No algorithm '{algorithm}'. Known algorithms: {known}.</source>
            <extracomment>algorithms/processing/registry.py:94</extracomment>
            <translation>Es gibt keinen Algorithmus '{algorithm}'. Bekannte Algorithmen: {known}.</translation>
        </message>
        <message>
            <source>Parameter '{name}': the output '{path}' is or contains the run folder '{folder}', where the batch writes its logs; choose another output.</source>
            <extracomment>algorithms/processing/registry.py:182</extracomment>
            <translation>Parameter '{name}': Die Ausgabe '{path}' ist oder enthält den Laufordner '{folder}', in den der Batch seine Protokolle schreibt; wählen Sie eine andere Ausgabe.</translation>
        </message>
        <message>
            <source>Parameter '{name}': {value} is not a valid {expected}.</source>
            <extracomment>algorithms/processing/spec.py:210</extracomment>
            <translation>Parameter '{name}': {value} ist kein gültiger Wert vom Typ „{expected}“.</translation>
        </message>
        <message>
            <source>Parameter '{name}': {value} is not one of {options}.</source>
            <extracomment>algorithms/processing/spec.py:261</extracomment>
            <translation>Parameter '{name}': {value} ist keiner der zulässigen Werte {options}.</translation>
        </message>
        <message>
            <source>{algorithm}: unknown parameter(s) {unknown}; known are {known}.</source>
            <extracomment>algorithms/processing/spec.py:421</extracomment>
            <translation>{algorithm}: unbekannte(r) Parameter {unknown}; bekannt sind {known}.</translation>
        </message>
        <message>
            <source>Parameter '{name}' must be a finite number, not {number}.</source>
            <extracomment>algorithms/processing/spec.py:241</extracomment>
            <translation>Parameter '{name}' muss eine endliche Zahl sein, nicht {number}.</translation>
        </message>
        <message>
            <source>Parameter '{name}' = {number:g}{unit} is outside the allowed range {low:g}…{high:g}{unit}.</source>
            <extracomment>algorithms/processing/spec.py:247</extracomment>
            <translation>Parameter '{name}' = {number:g}{unit} liegt außerhalb des zulässigen Bereichs {low:g}…{high:g}{unit}.</translation>
        </message>
        <message>
            <source>Parameter '{name}' ({description}) is required.</source>
            <extracomment>algorithms/processing/spec.py:189</extracomment>
            <translation>Parameter '{name}' ({description}) muss angegeben werden.</translation>
        </message>
        <message>
            <source>Parameter '{name}': the path '{path}' is not valid UTF-8; rename it (GDAL reads and writes UTF-8 names only).</source>
            <extracomment>algorithms/processing/spec.py:222</extracomment>
            <translation>Parameter '{name}': Der Pfad '{path}' ist kein gültiges UTF-8; benennen Sie ihn um (GDAL liest und schreibt nur UTF-8-Namen).</translation>
        </message>
        <message>
            <source>number</source>
            <extracomment>algorithms/processing/spec.py:267</extracomment>
            <translation>Zahl</translation>
        </message>
        <message>
            <source>whole number</source>
            <extracomment>algorithms/processing/spec.py:268</extracomment>
            <translation>ganze Zahl</translation>
        </message>
        <message>
            <source>yes/no value (true/false)</source>
            <extracomment>algorithms/processing/spec.py:269</extracomment>
            <translation>Ja/Nein-Wert (true/false)</translation>
        </message>
        <message>
            <source>extent 'xmin,ymin,xmax,ymax'</source>
            <extracomment>algorithms/processing/spec.py:270</extracomment>
            <translation>Ausdehnung 'xmin,ymin,xmax,ymax'</translation>
        </message>
        <message>
            <source>Parameter '{name}': '{path}' does not exist.</source>
            <extracomment>algorithms/processing/spec.py:429</extracomment>
            <translation>Parameter '{name}': '{path}' existiert nicht.</translation>
        </message>
        <message>
            <source>Breakline {number} crosses itself; fix it in edits.gpkg (layer breaklines).</source>
            <extracomment>algorithms/project/breaklines.py:78</extracomment>
            <translation>Die Bruchkante {number} kreuzt sich selbst; korrigieren Sie sie in edits.gpkg (Layer breaklines).</translation>
        </message>
        <message>
            <source>Breaklines {first} and {second} cross at ({x:.2f}, {y:.2f}); breaklines must not cross or touch — fix them in edits.gpkg.</source>
            <extracomment>algorithms/project/breaklines.py:87</extracomment>
            <translation>Die Bruchkanten {first} und {second} kreuzen sich bei ({x:.2f}, {y:.2f}); Bruchkanten dürfen sich weder kreuzen noch berühren — korrigieren Sie sie in edits.gpkg.</translation>
        </message>
        <message>
            <source>Surface '{path}' not found; choose a DSM or DTM of the project.</source>
            <extracomment>algorithms/project/edit_tools.py:106</extracomment>
            <translation>Oberfläche '{path}' nicht gefunden; wählen Sie ein DOM oder DGM des Projekts.</translation>
        </message>
        <message>
            <source>A line needs at least two vertices.</source>
            <extracomment>algorithms/project/edit_tools.py:269</extracomment>
            <translation>Eine Linie braucht mindestens zwei Stützpunkte.</translation>
        </message>
        <message>
            <source>Height mode '{mode}' is not one of drape, interpolate.</source>
            <extracomment>algorithms/project/edit_tools.py:274</extracomment>
            <translation>Der Höhenmodus '{mode}' ist weder drape noch interpolate.</translation>
        </message>
        <message>
            <source>Choose a surface (DSM or DTM) to drape the line on, or type the end heights to interpolate between them.</source>
            <extracomment>algorithms/project/edit_tools.py:276</extracomment>
            <translation>Wählen Sie eine Oberfläche (DOM oder DGM), auf die die Linie gelegt wird, oder geben Sie die Endhöhen ein, um zwischen ihnen zu interpolieren.</translation>
        </message>
        <message>
            <source>Type the heights of the first and the last vertex to interpolate between them.</source>
            <extracomment>algorithms/project/edit_tools.py:292</extracomment>
            <translation>Geben Sie die Höhen des ersten und des letzten Stützpunkts ein, um zwischen ihnen zu interpolieren.</translation>
        </message>
        <message>
            <source>The end heights ({z0}, {z1}) must be numbers (m).</source>
            <extracomment>algorithms/project/edit_tools.py:296</extracomment>
            <translation>Die Endhöhen ({z0}, {z1}) müssen Zahlen sein (m).</translation>
        </message>
        <message>
            <source>The line has no length; its first and last vertex are the same point.</source>
            <extracomment>algorithms/project/edit_tools.py:299</extracomment>
            <translation>Die Linie hat keine Länge; ihr erster und letzter Stützpunkt sind derselbe Punkt.</translation>
        </message>
        <message>
            <source>The layer '{layer}' has no heights to re-drape; use one of {layers}.</source>
            <extracomment>algorithms/project/edit_tools.py:357</extracomment>
            <translation>Der Layer '{layer}' hat keine Höhen, die neu abgegriffen werden können; verwenden Sie einen von {layers}.</translation>
        </message>
        <message>
            <source>The snapping tolerance must be positive, got {tolerance}.</source>
            <extracomment>algorithms/project/edit_tools.py:408</extracomment>
            <translation>Die Fangtoleranz muss positiv sein, angegeben: {tolerance}.</translation>
        </message>
        <message>
            <source>Surface '{name}' has no CRS, so a point in {crs} cannot be placed on it; assign the surface its CRS first.</source>
            <extracomment>algorithms/project/edit_tools.py:122</extracomment>
            <translation>Die Oberfläche '{name}' hat kein KBS, daher kann ein Punkt in {crs} nicht auf ihr platziert werden; weisen Sie der Oberfläche zuerst ihr KBS zu.</translation>
        </message>
        <message>
            <source>The point CRS '{crs}' is not understood: {error}</source>
            <extracomment>algorithms/project/edit_tools.py:131</extracomment>
            <translation>Das KBS der Punkte '{crs}' wird nicht verstanden: {error}</translation>
        </message>
        <message>
            <source>'{file}' layer {layer}, feature {fid}</source>
            <extracomment>algorithms/project/edits.py:74</extracomment>
            <translation>'{file}' Layer {layer}, Objekt {fid}</translation>
        </message>
        <message>
            <source>{where}: action '{value}' is not one of {actions} (empty = remove); fix it in edits.gpkg.</source>
            <extracomment>algorithms/project/edits.py:90</extracomment>
            <translation>{where}: Die Aktion '{value}' ist keine von {actions} (leer = remove); korrigieren Sie sie in edits.gpkg.</translation>
        </message>
        <message>
            <source>{where}: the polygon is invalid ({reason}) and nothing is left after repairing it; redraw it in edits.gpkg.</source>
            <extracomment>algorithms/project/edits.py:144</extracomment>
            <translation>{where}: Das Polygon ist ungültig ({reason}), und nach der Reparatur bleibt nichts übrig; zeichnen Sie es in edits.gpkg neu.</translation>
        </message>
        <message>
            <source>'{path}' exists already; PhotoDEM does not overwrite the operator's edits. Delete or rename it first if you really want an empty one.</source>
            <extracomment>algorithms/project/edits.py:213</extracomment>
            <translation>'{path}' existiert bereits; PhotoDEM überschreibt keine Bearbeitungen des Operateurs. Löschen oder benennen Sie die Datei zuerst um, wenn Sie wirklich eine leere möchten.</translation>
        </message>
        <message>
            <source>'{layer}' is not an edit layer; use one of {layers}.</source>
            <extracomment>algorithms/project/edits.py:303; algorithms/project/edits_save.py:361</extracomment>
            <translation>'{layer}' ist kein Bearbeitungslayer; verwenden Sie einen von {layers}.</translation>
        </message>
        <message>
            <source>Layer '{layer}' has no field(s) {fields}.</source>
            <extracomment>algorithms/project/edits.py:323</extracomment>
            <translation>Der Layer '{layer}' hat kein(e) Feld(er) {fields}.</translation>
        </message>
        <message>
            <source>Edits file '{path}' not found; create it with project_create.</source>
            <extracomment>algorithms/project/edits.py:360</extracomment>
            <translation>Bearbeitungsdatei '{path}' nicht gefunden; legen Sie sie mit project_create an.</translation>
        </message>
        <message>
            <source>Vector file '{path}' does not exist.</source>
            <extracomment>algorithms/project/edits.py:385</extracomment>
            <translation>Die Vektordatei '{path}' existiert nicht.</translation>
        </message>
        <message>
            <source>Cannot use the CRS '{crs}' for edits.gpkg: {error}</source>
            <extracomment>algorithms/project/edits.py:189</extracomment>
            <translation>Das KBS '{crs}' kann für edits.gpkg nicht verwendet werden: {error}</translation>
        </message>
        <message>
            <source>Layer '{layer}'</source>
            <extracomment>algorithms/project/edits.py:326</extracomment>
            <translation>Layer '{layer}'</translation>
        </message>
        <message>
            <source>'{path}' has no layer '{layer}'.</source>
            <extracomment>algorithms/project/edits.py:365</extracomment>
            <translation>'{path}' hat keinen Layer '{layer}'.</translation>
        </message>
        <message>
            <source>A geometry of edits.gpkg is not a GeoPackage geometry blob.</source>
            <extracomment>algorithms/project/edits_save.py:80</extracomment>
            <translation>Eine Geometrie in edits.gpkg ist kein GeoPackage-Geometrie-Blob.</translation>
        </message>
        <message>
            <source>The edits file '{path}' does not exist.</source>
            <extracomment>algorithms/project/edits_save.py:199</extracomment>
            <translation>Die Bearbeitungsdatei '{path}' existiert nicht.</translation>
        </message>
        <message>
            <source>Two features of one edit layer have the same fid.</source>
            <extracomment>algorithms/project/edits_save.py:241</extracomment>
            <translation>Zwei Objekte eines Bearbeitungslayers haben dieselbe fid.</translation>
        </message>
        <message>
            <source>Layer '{layer}' of edits.gpkg has no field(s) {fields}.</source>
            <extracomment>algorithms/project/edits_save.py:257</extracomment>
            <translation>Der Layer '{layer}' von edits.gpkg hat kein(e) Feld(er) {fields}.</translation>
        </message>
        <message>
            <source>Cannot open the edits file '{path}': {error}</source>
            <extracomment>algorithms/project/edits_save.py:203</extracomment>
            <translation>Die Bearbeitungsdatei '{path}' kann nicht geöffnet werden: {error}</translation>
        </message>
        <message>
            <source>The edits file '{path}' is not a readable GeoPackage ({error}); it is damaged or not a GeoPackage.</source>
            <extracomment>algorithms/project/edits_save.py:214</extracomment>
            <translation>Die Bearbeitungsdatei '{path}' ist kein lesbares GeoPackage ({error}); sie ist beschädigt oder kein GeoPackage.</translation>
        </message>
        <message>
            <source>The edits file '{path}' holds a geometry that cannot be read ({error}).</source>
            <extracomment>algorithms/project/edits_save.py:217</extracomment>
            <translation>Die Bearbeitungsdatei '{path}' enthält eine Geometrie, die nicht gelesen werden kann ({error}).</translation>
        </message>
        <message>
            <source>The new edits.gpkg holds {count} features in '{layer}' instead of {expected}; the old file is kept.</source>
            <extracomment>algorithms/project/edits_save.py:325</extracomment>
            <translation>Die neue edits.gpkg enthält {count} Objekte in '{layer}' statt {expected}; die alte Datei bleibt erhalten.</translation>
        </message>
        <message>
            <source>Cannot write '{path}': {error}; the old file is kept.</source>
            <extracomment>algorithms/project/edits_save.py:380</extracomment>
            <translation>'{path}' kann nicht geschrieben werden: {error}; die alte Datei bleibt erhalten.</translation>
        </message>
        <message>
            <source>The new edits.gpkg cannot be read back ({error}); the old file is kept.</source>
            <extracomment>algorithms/project/edits_save.py:322</extracomment>
            <translation>Die neue edits.gpkg kann nicht zurückgelesen werden ({error}); die alte Datei bleibt erhalten.</translation>
        </message>
        <message>
            <source>'{path}' does not exist and no CRS was given to create it.</source>
            <extracomment>algorithms/project/edits_save.py:369</extracomment>
            <translation>'{path}' existiert nicht, und zum Anlegen wurde kein KBS angegeben.</translation>
        </message>
        <message>
            <source>edits.gpkg has no layer '{layer}' to write.</source>
            <extracomment>algorithms/project/edits_save.py:308</extracomment>
            <translation>edits.gpkg hat keinen Layer '{layer}' zum Schreiben.</translation>
        </message>
        <message>
            <source>camera</source>
            <extracomment>algorithms/project/model.py:77</extracomment>
            <translation>Kamera</translation>
        </message>
        <message>
            <source>stereo model</source>
            <extracomment>algorithms/project/model.py:78</extracomment>
            <translation>Stereomodell</translation>
        </message>
        <message>
            <source>{where}: the {what} name {shown} cannot be used: {problem}. Names become folder names; use letters, digits, '-' and '_'.</source>
            <extracomment>algorithms/project/model.py:107</extracomment>
            <translation>{where}: Der {what}name {shown} kann nicht verwendet werden: {problem}. Namen werden zu Ordnernamen; verwenden Sie Buchstaben, Ziffern, '-' und '_'.</translation>
        </message>
        <message>
            <source>{where}: 'format_version' is {version} but this PhotoDEM reads format_version {supported} only: {why}.</source>
            <extracomment>algorithms/project/model.py:507</extracomment>
            <translation>{where}: 'format_version' ist {version}, diese PhotoDEM-Version liest aber nur format_version {supported}: {why}.</translation>
        </message>
        <message>
            <source>it must be text, not {type}</source>
            <extracomment>algorithms/project/model.py:60</extracomment>
            <translation>er muss Text sein, nicht {type}</translation>
        </message>
        <message>
            <source>it is empty</source>
            <extracomment>algorithms/project/model.py:62</extracomment>
            <translation>er ist leer</translation>
        </message>
        <message>
            <source>it contains a path separator ('/' or '\')</source>
            <extracomment>algorithms/project/model.py:64</extracomment>
            <translation>er enthält einen Pfadtrenner ('/' oder '\')</translation>
        </message>
        <message>
            <source>'.' and '..' name folders</source>
            <extracomment>algorithms/project/model.py:66</extracomment>
            <translation>'.' und '..' bezeichnen Ordner</translation>
        </message>
        <message>
            <source>it starts with a dot</source>
            <extracomment>algorithms/project/model.py:68</extracomment>
            <translation>er beginnt mit einem Punkt</translation>
        </message>
        <message>
            <source>it contains a control character</source>
            <extracomment>algorithms/project/model.py:70</extracomment>
            <translation>er enthält ein Steuerzeichen</translation>
        </message>
        <message>
            <source>it is not valid UTF-8 text</source>
            <extracomment>algorithms/project/model.py:72</extracomment>
            <translation>er ist kein gültiger UTF-8-Text</translation>
        </message>
        <message>
            <source>Image '{name}' is not in project '{project}'. Images: {images}.</source>
            <extracomment>algorithms/project/model.py:269</extracomment>
            <translation>Das Bild '{name}' ist nicht im Projekt '{project}'. Bilder: {images}.</translation>
        </message>
        <message>
            <source>Stereo model '{name}' is not in project '{project}'. Models: {models}.</source>
            <extracomment>algorithms/project/model.py:281</extracomment>
            <translation>Das Stereomodell '{name}' ist nicht im Projekt '{project}'. Modelle: {models}.</translation>
        </message>
        <message>
            <source>it was written by a newer PhotoDEM; update PhotoDEM to open it</source>
            <extracomment>algorithms/project/model.py:505</extracomment>
            <translation>die Datei stammt von einer neueren PhotoDEM-Version; aktualisieren Sie PhotoDEM, um sie zu öffnen</translation>
        </message>
        <message>
            <source>no PhotoDEM wrote it; fix the value</source>
            <extracomment>algorithms/project/model.py:506</extracomment>
            <translation>keine PhotoDEM-Version hat sie geschrieben; korrigieren Sie den Wert</translation>
        </message>
        <message>
            <source>{where}: '{key}' {problem}; fix it in the project file.</source>
            <extracomment>algorithms/project/model.py:555</extracomment>
            <translation>{where}: '{key}' {problem}; korrigieren Sie dies in der Projektdatei.</translation>
        </message>
        <message>
            <source>Stereo model '{name}' is not in project '{project}'. Models: none.</source>
            <extracomment>algorithms/project/model.py:279</extracomment>
            <translation>Das Stereomodell '{name}' ist nicht im Projekt '{project}'. Das Projekt hat keine Stereomodelle.</translation>
        </message>
        <message>
            <source>'{path}' is not a PhotoDEM project: {file} not found. Create one with project_create or synthetic_block.</source>
            <extracomment>algorithms/project/model.py:407</extracomment>
            <translation>'{path}' ist kein PhotoDEM-Projekt: {file} wurde nicht gefunden. Legen Sie eines mit project_create oder synthetic_block an.</translation>
        </message>
        <message>
            <source>{where} has no [project] table (it is not a PhotoDEM project file); restore it from a copy or create the project again with project_create.</source>
            <extracomment>algorithms/project/model.py:429</extracomment>
            <translation>{where} hat keine Tabelle [project] (es ist keine PhotoDEM-Projektdatei); stellen Sie die Datei aus einer Kopie wieder her oder legen Sie das Projekt mit project_create neu an.</translation>
        </message>
        <message>
            <source>{where} is not UTF-8 text (byte 0x{byte:02x} at position {position}); save it as UTF-8.</source>
            <extracomment>algorithms/project/model.py:414</extracomment>
            <translation>{where} ist kein UTF-8-Text (Byte 0x{byte:02x} an Position {position}); speichern Sie die Datei als UTF-8.</translation>
        </message>
        <message>
            <source>{where} is not valid TOML ({error}); fix the line it names.</source>
            <extracomment>algorithms/project/model.py:418</extracomment>
            <translation>{where} ist kein gültiges TOML ({error}); korrigieren Sie die genannte Zeile.</translation>
        </message>
        <message>
            <source>Cannot read {where}: {error}.</source>
            <extracomment>algorithms/project/model.py:421</extracomment>
            <translation>{where} kann nicht gelesen werden: {error}.</translation>
        </message>
        <message>
            <source>{where} has no [project] table (it is empty); restore it from a copy or create the project again with project_create.</source>
            <extracomment>algorithms/project/model.py:426</extracomment>
            <translation>{where} hat keine Tabelle [project] (die Datei ist leer); stellen Sie sie aus einer Kopie wieder her oder legen Sie das Projekt mit project_create neu an.</translation>
        </message>
        <message>
            <source>{where}: {error}</source>
            <extracomment>algorithms/project/model.py:437; algorithms/project/model.py:651</extracomment>
            <translation>{where}: {error}</translation>
        </message>
        <message>
            <source>is missing</source>
            <extracomment>algorithms/project/model.py:562</extracomment>
            <translation>fehlt</translation>
        </message>
        <message>
            <source>must be text in quotes, not {value}</source>
            <extracomment>algorithms/project/model.py:570</extracomment>
            <translation>muss Text in Anführungszeichen sein, nicht {value}</translation>
        </message>
        <message>
            <source>must be a number, not {value}</source>
            <extracomment>algorithms/project/model.py:580</extracomment>
            <translation>muss eine Zahl sein, nicht {value}</translation>
        </message>
        <message>
            <source>must be a whole number, not {value}</source>
            <extracomment>algorithms/project/model.py:587</extracomment>
            <translation>muss eine ganze Zahl sein, nicht {value}</translation>
        </message>
        <message>
            <source>must be a list of {length} numbers, not {value}</source>
            <extracomment>algorithms/project/model.py:598</extracomment>
            <translation>muss eine Liste von {length} Zahlen sein, nicht {value}</translation>
        </message>
        <message>
            <source>must be a table ([{key}]), not {value}</source>
            <extracomment>algorithms/project/model.py:606</extracomment>
            <translation>muss eine Tabelle ([{key}]) sein, nicht {value}</translation>
        </message>
        <message>
            <source>must be an array of tables ([[{key}]]), not {value}</source>
            <extracomment>algorithms/project/model.py:615</extracomment>
            <translation>muss eine Liste von Tabellen ([[{key}]]) sein, nicht {value}</translation>
        </message>
        <message>
            <source>must be a table, not {value}</source>
            <extracomment>algorithms/project/model.py:624</extracomment>
            <translation>muss eine Tabelle sein, nicht {value}</translation>
        </message>
        <message>
            <source>must be 2 rows of 3 numbers, not {value}</source>
            <extracomment>algorithms/project/model.py:646</extracomment>
            <translation>muss aus 2 Zeilen mit je 3 Zahlen bestehen, nicht {value}</translation>
        </message>
        <message>
            <source>Cannot read the {what} '{name}': {error}</source>
            <extracomment>algorithms/project/vector_io.py:61</extracomment>
            <translation>'{name}' kann nicht als {what} gelesen werden: {error}</translation>
        </message>
        <message>
            <source>The output '{path}' is a file, not a folder; choose a folder.</source>
            <extracomment>algorithms/raster/io.py:223</extracomment>
            <translation>Die Ausgabe '{path}' ist eine Datei, kein Ordner; wählen Sie einen Ordner.</translation>
        </message>
        <message>
            <source>The output folder '{path}' is a PhotoDEM project; choose another folder (a project is never replaced).</source>
            <extracomment>algorithms/raster/io.py:228</extracomment>
            <translation>Der Ausgabeordner '{path}' ist ein PhotoDEM-Projekt; wählen Sie einen anderen Ordner (ein Projekt wird nie ersetzt).</translation>
        </message>
        <message>
            <source>The output folder '{path}' exists and is not empty; choose a new folder (PhotoDEM does not overwrite earlier results here).</source>
            <extracomment>algorithms/raster/io.py:231</extracomment>
            <translation>Der Ausgabeordner '{path}' existiert bereits und ist nicht leer; wählen Sie einen neuen Ordner (PhotoDEM überschreibt hier keine früheren Ergebnisse).</translation>
        </message>
        <message>
            <source>The output folder '{path}' holds {what}; choose an empty or new folder (PhotoDEM only replaces earlier results of the same algorithm).</source>
            <extracomment>algorithms/raster/io.py:238</extracomment>
            <translation>Der Ausgabeordner '{path}' enthält {what}; wählen Sie einen leeren oder neuen Ordner (PhotoDEM ersetzt nur frühere Ergebnisse desselben Algorithmus).</translation>
        </message>
        <message>
            <source>Match foreshortened slopes (dense, convergent)</source>
            <translation type="vanished">Verkürzte Hänge zuordnen (dense, konvergent)</translation>
        </message>
        <message>
            <source>Convergent models only: also match against the right image stretched by 0.7 and 1.4, for slopes one camera sees foreshortened, refined by least-squares matching. More cells measured as precisely as the others, about 5 × the time.</source>
            <translation type="vanished">Nur konvergente Modelle: zusätzlich gegen das um 0,7 und 1,4 gestreckte rechte Bild zuordnen, für Hänge, die eine Kamera verkürzt sieht, verfeinert durch Kleinste-Quadrate-Zuordnung. Mehr Zellen gemessen, so genau wie die übrigen, etwa 5 × die Rechenzeit.</translation>
        </message>
        <message>
            <source>Convergent models only: also match against the right image stretched by 0.7 and 1.4, for slopes one camera sees foreshortened. More cells measured, a slightly higher NMAD on open terrain, about 5 × the time.</source>
            <translation type="vanished">Nur konvergente Modelle: zusätzlich gegen das um 0,7 und 1,4 gestreckte rechte Bild zuordnen, für Hänge, die eine Kamera verkürzt sieht. Mehr Zellen gemessen, etwas höhere NMAD im offenen Gelände, etwa 5 × die Rechenzeit.</translation>
        </message>
        <message>
            <source>general (default): keeps buildings and trees with sharp walls (a DSM) and open terrain as accurate as terrain; urban: smaller windows and groundels for built-up areas; terrain (formerly flat): large windows and groundels, smooth surface without objects (nearly a DTM); hilly: medium; forest: lower envelope of the points per groundel. The options below override it.</source>
            <translation type="vanished">allgemein (Standard): behält Gebäude und Bäume mit scharfen Wänden (ein DOM) und offenes Gelände so genau wie Gelände; städtisch: kleinere Fenster und Geländeelemente für bebaute Gebiete; Gelände (früher flach): große Fenster und Geländeelemente, glatte Fläche ohne Objekte (fast ein DGM); hügelig: mittlere; Wald: untere Einhüllende der Punkte je Geländeelement. Die unten angegebenen Optionen überschreiben die Vorgabe.</translation>
        </message>
        <message>
            <source>A polygon layer in any CRS (matched in its projected CRS, or the UTM zone of its centre), or a georeferenced raster segmented like the image.</source>
            <translation type="vanished">Ein Polygonlayer in beliebigem KBS (zugeordnet in seinem projizierten KBS oder in der UTM-Zone seiner Mitte) oder ein georeferenziertes Raster, das wie das Bild segmentiert wird.</translation>
        </message>
        <message>
            <source>objects: match image regions to the polygons as objects; area: compare the whole image with the rasterised polygons (rotation and scale by Fourier–Mellin, shift by correlation, refined by ECC), and when that fails the polygons' individual outlines with the image's edge directions — for objects that are not homogeneous in the image, such as glaciers; auto: objects, and the area-based search when they give no result. Polygon layers only.</source>
            <translation type="vanished">objects: Bildregionen als Objekte den Polygonen zuordnen; area: das ganze Bild mit den gerasterten Polygonen vergleichen (Drehung und Maßstab nach Fourier–Mellin, Verschiebung durch Korrelation, Verfeinerung mit ECC) und, wenn das scheitert, die einzelnen Umrisse der Polygone mit den Kantenrichtungen des Bildes — für Objekte, die im Bild nicht homogen sind, etwa Gletscher; auto: Objekte, und die flächenbasierte Suche, wenn sie kein Ergebnis liefern. Nur für Polygonlayer.</translation>
        </message>
        <message>
            <source>Side of the window of the robust consistency. Default: the preset's.</source>
            <translation type="vanished">Seitenlänge des Fensters der robusten Konsistenzprüfung. Standard: laut Vorgabe.</translation>
        </message>
        <message>
            <source>tiny: 224×288 px images (tests); small: 704×1000 px (demo); medium: 1408×2000 px; large: 2400×3400 px (≈ 8 Mpx); aerial: three wide-angle film frames in one strip (11500 px, c = 153 mm, B/H 0.6, base 4600 px, H ≈ 1150 m) of which a 1024×1024 px window over the common ground patch is rendered — for height accuracy in ‰ of H.</source>
            <translation type="vanished">winzig: Bilder mit 224×288 px (Tests); klein: 704×1000 px (Demo); mittel: 1408×2000 px; groß: 2400×3400 px (≈ 8 Mpx); Luftbild: drei Weitwinkel-Filmbilder in einem Streifen (11500 px, c = 153 mm, B/H 0,6, Basis 4600 px, H ≈ 1150 m), von denen ein Fenster von 1024×1024 px über dem gemeinsam abgebildeten Geländeausschnitt gerendert wird — für die Höhengenauigkeit in ‰ von H.</translation>
        </message>
        <message>
            <source>default serves all terrain types; flat, hilly, urban, forest and steep are tuned variants. Options given below override the preset.</source>
            <translation type="vanished">default dient allen Geländetypen; flat, hilly, urban, forest und steep sind abgestimmte Varianten. Die unten angegebenen Optionen überschreiben die Vorgabe.</translation>
        </message>
        <message>
            <source>Creates a PhotoDEM project (project.toml + edits.gpkg) from a folder of images and their orientation: an OPK CSV or text file with the camera YAML (orthority format), or an OpenSfM/ODM reconstruction.json. The block is validated and its stereo models are detected (overlap ≥ 25 %, B/H 0.2–1.2, in-strip neighbours first).</source>
            <translation type="vanished">Legt ein PhotoDEM-Projekt (project.toml + edits.gpkg) aus einem Bildordner und der Orientierung der Bilder an: eine OPK-CSV- oder Textdatei mit der Kamera-YAML (Orthority-Format) oder eine OpenSfM/ODM-reconstruction.json. Der Bildverband wird geprüft und seine Stereomodelle werden bestimmt (Überlappung ≥ 25 %, B/H 0,2–1,2, Nachbarn im selben Streifen zuerst).</translation>
        </message>
        <message>
            <source>Exterior orientation (OPK CSV/text or reconstruction.json)</source>
            <translation type="vanished">Äußere Orientierung (OPK-CSV/-Text oder reconstruction.json)</translation>
        </message>
        <message>
            <source>Lists a project's CRS, images (position, angles in degrees, whether the file exists), cameras and stereo models (B/H, overlap %, GSD, flying height above ground), and the result of its validation. Validation warnings and errors are reported; a project with errors (a CRS PROJ does not know, no images, missing image files…) ends with an error naming the first of them.</source>
            <translation type="vanished">Listet KBS, Bilder (Position, Winkel in Grad, ob die Datei vorhanden ist), Kameras und Stereomodelle (B/H, Überlappung in %, Bodenauflösung, Flughöhe über Grund) eines Projekts sowie das Ergebnis seiner Prüfung auf. Warnungen und Fehler der Prüfung werden gemeldet; ein Projekt mit Fehlern (ein KBS, das PROJ nicht kennt, keine Bilder, fehlende Bilddateien …) endet mit einem Fehler, der den ersten davon nennt.</translation>
        </message>
        <message>
            <source>Choose an algorithm on the left.</source>
            <translation type="vanished">Links einen Algorithmus wählen.</translation>
        </message>
        <message>
            <source>urban (default): small windows and groundels, keeps buildings and trees with sharp walls (a DSM); terrain (formerly flat): large windows and groundels, smooth surface without objects (nearly a DTM); hilly: medium; forest: lower envelope of the points per groundel. The options below override it.</source>
            <translation type="vanished">städtisch (Standard): kleine Fenster und Geländeelemente, behält Gebäude und Bäume mit scharfen Wänden (ein DOM); Gelände (früher flach): große Fenster und Geländeelemente, glatte Fläche ohne Objekte (fast ein DGM); hügelig: mittlere; Wald: untere Einhüllende der Punkte je Geländeelement. Die unten angegebenen Optionen überschreiben die Vorgabe.</translation>
        </message>
        <message>
            <source>Side of the cells of the robust reduction. Default: the preset's multiple of the GSD (urban: 10 × GSD, terrain: 40 × GSD).</source>
            <translation type="vanished">Seitenlänge der Zellen der robusten Reduktion. Standard: das Vielfache der GSD laut Vorgabe (städtisch: 10 × GSD, Gelände: 40 × GSD).</translation>
        </message>
        <message>
            <source>flat: large windows and groundels, smooth surface; hilly: medium; urban: small windows and groundels, median, sharp edges; forest: lower envelope of the points per groundel. The options below override it.</source>
            <translation type="vanished">flach: große Fenster und Geländeelemente, glatte Fläche; hügelig: mittlere; städtisch: kleine Fenster und Geländeelemente, Median, scharfe Kanten; Wald: untere Einhüllende der Punkte je Geländeelement. Die unten angegebenen Optionen überschreiben die Vorgabe.</translation>
        </message>
        <message>
            <source>Side of the cells of the robust reduction. Default: the preset's multiple of the GSD (flat: 40 × GSD).</source>
            <translation type="vanished">Seitenlänge der Zellen der robusten Reduktion. Standard: das Vielfache der GSD laut Vorgabe (flach: 40 × GSD).</translation>
        </message>
        <message>
            <source>Compares a DEM (DSM or DTM) with a reference DEM on their common area; the reference may have another grid, extent or CRS (the DEM is resampled onto it). Optionally co-registers the DEM first (horizontal shift and vertical bias after Nuth &amp; Kääb, estimated on stable terrain). Writes the difference model Δh = DEM − reference (with a QGIS style), a hillshade and a slope raster of the DEM, statistics (mean, median, std, RMS, NMAD, quantiles of |Δh|, 0.5 m classes) overall, per class and per slope class, in m and in ‰ of the flying height, and an HTML report with plots.</source>
            <translation type="vanished">Vergleicht ein Höhenmodell (DOM oder DGM) im gemeinsamen Gebiet mit einem Referenzmodell; das Referenzmodell darf ein anderes Raster, eine andere Ausdehnung oder ein anderes KBS haben (das Höhenmodell wird darauf umgerechnet). Optional wird das Höhenmodell vorher koregistriert (Lageverschiebung und Höhenversatz nach Nuth &amp; Kääb, geschätzt auf stabilem Gelände). Schreibt das Differenzmodell Δh = Höhenmodell − Referenz (mit QGIS-Stil), eine Schummerung und ein Neigungsraster des Höhenmodells, Statistiken (Mittel, Median, Standardabweichung, RMS, NMAD, Quantile von |Δh|, 0,5-m-Klassen) insgesamt, je Klasse und je Neigungsklasse, in m und in ‰ der Flughöhe, sowie einen HTML-Bericht mit Diagrammen.</translation>
        </message>
        <message>
            <source>Receives difference.tif (+ .qml style), hillshade.tif, slope.tif, report.html, stats.json and stats.csv.</source>
            <translation type="vanished">Erhält difference.tif (+ .qml-Stil), hillshade.tif, slope.tif, report.html, stats.json und stats.csv.</translation>
        </message>
        <message>
            <source>Finds the georeference of an image without approximate values (position, scale, rotation and mirroring unknown) by matching area objects: the image is segmented by region growing at several thresholds, its regions and the reference polygons (one class of a vector layer, touching polygons dissolved — or a segmented orthophoto) are described by affine-invariant moment features, corresponding objects are found by a consistency search, verified, refined by ICP, and control points on their outlines give the final transform (affine, projective or 2nd-order polynomial). When no objects match (objects not homogeneous in the image), an area-based search compares the whole image with the rasterised polygons instead. Writes a QGIS Georeferencer .points file, the control points as GeoPackage, the image resampled into the map CRS, a copy with the control points embedded and a report (overlay, residuals, RMSE in px and m). Too few matching objects give a failure message with the counts of every stage, not a wrong result.</source>
            <translation type="vanished">Bestimmt die Georeferenz eines Bildes ohne Näherungswerte (Position, Maßstab, Drehung und Spiegelung unbekannt) durch Zuordnung von Flächenobjekten: Das Bild wird mit mehreren Schwellen durch Bereichswachstum segmentiert, seine Regionen und die Referenzpolygone (eine Klasse eines Vektorlayers, aneinandergrenzende Polygone verschmolzen — oder ein segmentiertes Orthophoto) werden durch affin-invariante Momentmerkmale beschrieben, zugehörige Objekte durch eine Konsistenzsuche gefunden, verifiziert und mit ICP verfeinert; Passpunkte auf ihren Konturen ergeben die endgültige Transformation (affin, projektiv oder Polynom 2. Grades). Passen keine Objekte zusammen (Objekte im Bild nicht homogen), vergleicht stattdessen eine flächenbasierte Suche das ganze Bild mit den gerasterten Polygonen. Schreibt eine .points-Datei des QGIS-Georeferenzierers, die Passpunkte als GeoPackage, das in das Karten-KBS umgebildete Bild, eine Kopie mit eingebetteten Passpunkten und einen Bericht (Überlagerung, Residuen, RMSE in px und m). Zu wenige zugeordnete Objekte ergeben eine Fehlermeldung mit den Anzahlen jeder Stufe, kein falsches Ergebnis.</translation>
        </message>
        <message>
            <source>objects: match image regions to the polygons as objects; area: compare the whole image with the rasterised polygons (rotation and scale by Fourier–Mellin, shift by correlation, refined by ECC) — for objects that are not homogeneous in the image; auto: objects, and the area-based search when they give no result. Polygon layers only.</source>
            <translation type="vanished">objects: Bildregionen als Objekte den Polygonen zuordnen; area: das ganze Bild mit den gerasterten Polygonen vergleichen (Drehung und Maßstab nach Fourier–Mellin, Verschiebung durch Korrelation, Verfeinerung mit ECC) — für Objekte, die im Bild nicht homogen sind; auto: Objekte, und die flächenbasierte Suche, wenn sie kein Ergebnis liefern. Nur für Polygonlayer.</translation>
        </message>
        <message>
            <source>Indirect differential rectification of one image of the project onto a DEM: for every output cell the height comes from the DEM (bilinear), the cell is projected into the image by the collinearity equations (with distortion) and the image is resampled there (nearest, bilinear or cubic), tile by tile. A DTM gives a classical ortho (buildings lean away from the nadir by Δr = h·r/H); a true ortho needs the DSM: cells the camera cannot see because a building or tree hides them are marked occluded (alpha 0, visibility 2) so that a mosaic fills them from another image. Writes a tiled GeoTIFF with overviews (the image bands plus an alpha band) and &lt;name&gt;_visibility.tif (0 outside the image, 1 visible, 2 occluded). A DEM in another CRS is reprojected on the fly (with a warning).</source>
            <translation type="vanished">Indirekte differentielle Entzerrung eines Bildes des Projekts auf ein DGM: Für jede Ausgabezelle kommt die Höhe aus dem DGM (bilinear), die Zelle wird mit den Kollinearitätsgleichungen (mit Verzeichnung) ins Bild projiziert und das Bild dort neu abgetastet (nächster Nachbar, bilinear oder kubisch), Kachel für Kachel. Ein DGM ergibt ein klassisches Orthofoto (Gebäude kippen um Δr = h·r/H vom Nadir weg); ein True-Ortho braucht das DOM: Zellen, die die Kamera nicht sieht, weil ein Gebäude oder Baum sie verdeckt, werden als verdeckt markiert (Alpha 0, Sichtbarkeit 2), damit ein Mosaik sie aus einem anderen Bild füllt. Schreibt ein gekacheltes GeoTIFF mit Übersichten (die Bildkanäle plus ein Alphakanal) und &lt;name&gt;_visibility.tif (0 außerhalb des Bildes, 1 sichtbar, 2 verdeckt). Ein DGM in einem anderen KBS wird während der Verarbeitung umprojiziert (mit einer Warnung).</translation>
        </message>
        <message>
            <source>Mosaics orthos into one tiled GeoTIFF with overviews (colour bands + alpha). Inputs: orthos (PhotoDEM orthos carry their projection centre), or a project and a DEM: then every image is rectified first (a true ortho on the DSM with true_ortho). Seamlines: auto starts from the nadir partition (each cell to the image with the nearest projection centre) and routes every seam along a least-cost path through low image difference and low DSM height above the DTM (give dsm and dtm), so seams do not cut through buildings or trees; nadir keeps the partition; edits takes the 'seamlines' layer of the project's edits.gpkg; or give a vector file: lines cut the area (each part to the image nearest in nadir), polygons with an 'image' attribute take their area from that image (the footprints layer a mosaic writes can be edited and reused). Occluded cells (alpha 0) are filled from the next best image. Balancing: gain and offset per image and band by least squares over all overlaps (gain_offset), plus histogram matching (histogram), or none; feathering blends across seams over the given width. Writes the mosaic, &lt;name&gt;_seamlines.gpkg (footprints: one polygon per source image; seamlines) and &lt;name&gt;_balance.json (gains, offsets, mean difference of the overlaps before and after). Works tile by tile; seams and balancing use a seam grid of at most seam_cells cells a side, so memory does not grow with the mosaic.</source>
            <translation type="vanished">Fügt Orthophotos zu einem gekachelten GeoTIFF mit Übersichten zusammen (Farbkanäle + Alpha). Eingaben: Orthophotos (PhotoDEM-Orthophotos tragen ihr Projektionszentrum) oder ein Projekt und ein DGM: dann wird zuerst jedes Bild entzerrt (mit true_ortho ein True-Ortho auf dem DOM). Schnittlinien: auto beginnt mit der Nadir-Aufteilung (jede Zelle zum Bild mit dem nächsten Projektionszentrum) und führt jede Schnittlinie auf einem Weg geringster Kosten durch geringe Bilddifferenz und geringe Höhe des DOM über dem DGM (dsm und dtm angeben), sodass Schnittlinien keine Gebäude oder Bäume zerschneiden; nadir behält die Aufteilung; edits nimmt die Ebene 'seamlines' der edits.gpkg des Projekts; oder eine Vektordatei angeben: Linien zerschneiden die Fläche (jeder Teil zum im Nadir nächsten Bild), Polygone mit einem Attribut 'image' nehmen ihre Fläche aus diesem Bild (die Ebene footprints, die ein Mosaik schreibt, kann bearbeitet und wiederverwendet werden). Verdeckte Zellen (Alpha 0) werden aus dem nächstbesten Bild gefüllt. Ausgleich: Verstärkung und Versatz je Bild und Kanal durch Ausgleichung über alle Überlappungen (gain_offset), zusätzlich Histogrammanpassung (histogram) oder keiner; Überblendung über die angegebene Breite an den Schnittlinien. Schreibt das Mosaik, &lt;Name&gt;_seamlines.gpkg (footprints: ein Polygon je Quellbild; seamlines) und &lt;Name&gt;_balance.json (Verstärkungen, Versätze, mittlere Differenz der Überlappungen vorher und nachher). Arbeitet kachelweise; Schnittlinien und Ausgleich nutzen ein Schnittliniengitter mit höchstens seam_cells Zellen je Seite, sodass der Speicherbedarf nicht mit dem Mosaik wächst.</translation>
        </message>
        <message>
            <source>Generates a deterministic synthetic aerial block: terrain (gentle, dunes or steep), an embankment and a ditch with breaklines, buildings, trees and a forest patch, textured ground with bright check-point discs, frame images in two or more strips (60 % forward, 30 % side overlap) rendered by ray casting against the true DSM. Writes a complete project (project.toml, images, edits.gpkg, in-strip stereo models) and the ground truth (DTM, DSM, land cover, building footprints, 3-D breaklines, check points) below truth/. The same seed always gives the same block.</source>
            <translation type="vanished">Erzeugt einen deterministischen synthetischen Bildflug: Gelände (flach, Dünen oder steil), einen Damm und einen Graben mit Bruchkanten, Gebäude, Bäume und ein Waldstück, texturierten Boden mit hellen Kontrollpunktscheiben sowie Reihenmessbilder in zwei oder mehr Streifen (60 % Längs-, 30 % Querüberdeckung), gerendert durch Strahlverfolgung gegen das wahre Oberflächenmodell. Schreibt ein vollständiges Projekt (project.toml, Bilder, edits.gpkg, Stereomodelle im Streifen) und die Referenzdaten (Geländemodell, Oberflächenmodell, Landbedeckung, Gebäudegrundrisse, 3D-Bruchkanten, Kontrollpunkte) unter truth/. Derselbe Startwert ergibt immer denselben Bildverband.</translation>
        </message>
        <message>
            <source>tiny: 224×288 px images (tests); small: 704×1000 px (demo); medium: 1408×2000 px; large: 2400×3400 px (≈ 8 Mpx).</source>
            <translation type="vanished">winzig: Bilder mit 224×288 px (Tests); klein: 704×1000 px (Demo); mittel: 1408×2000 px; groß: 2400×3400 px (≈ 8 Mpx).</translation>
        </message>
        <message>
            <source>Matches the two images of a stereo model and grids the points to a DSM. dense: epipolar resampling, semi-global matching with left–right check, triangulation of every valid disparity, median per DSM cell, interpolation of small gaps that does not cross breaklines; exclusion areas and boundaries of edits.gpkg are honoured (NaN). Writes dsm.tif (float32, NaN = no height), count.tif (points per cell) and report.json (points, coverage, valid disparities, timings).</source>
            <translation type="vanished">Ordnet die beiden Bilder eines Stereomodells zu und rastert die Punkte zu einem DOM. dense: Epipolarumbildung, Semi-Global Matching mit Links–Rechts-Prüfung, Vorwärtsschnitt jeder gültigen Disparität, Median je DOM-Zelle, Interpolation kleiner Lücken, die Bruchkanten nicht überquert; Ausschlussflächen und Begrenzungen aus edits.gpkg werden beachtet (NaN). Schreibt dsm.tif (float32, NaN = keine Höhe), count.tif (Punkte je Zelle) und report.json (Punkte, Abdeckung, gültige Disparitäten, Zeiten).</translation>
        </message>
        <message>
            <source>dense: semi-global matching of every pixel on the epipolar pair.</source>
            <translation type="vanished">dense: Semi-Global Matching jedes Pixels im Epipolarpaar.</translation>
        </message>
        <message>
            <source>Default: 1 × the model's ground sample distance.</source>
            <translation type="vanished">Standard: 1 × Bodenpixelgröße des Modells.</translation>
        </message>
        <message>
            <source>Larger gaps stay empty (NaN). Default: 10 × spacing.</source>
            <translation type="vanished">Größere Lücken bleiben leer (NaN). Standard: 10 × Gitterweite.</translation>
        </message>
        <message>
            <source>Points (not written yet)</source>
            <translation type="vanished">Punkte (noch nicht geschrieben)</translation>
        </message>
    </context>
</TS>
