// Venue mode for the Recorder: tracks the venue's printed anchor image with AR Foundation's
// ARTrackedImageManager and reports every observation to the session, loads the venue map
// and draws its layer once the anchor has been fully tracked (surface cells as translucent
// tiles by class, path cells as a faint trail; a button toggles it), draws arrows at the
// screen's edge to markers and high venue cells out of view (SitarSession.Guide), and pulses
// each marker for its first seconds in view (a kineticon). The logic is in SitarVenueView.cs.
using System.Collections.Generic;
using UnityEngine;
using UnityEngine.UI;
using UnityEngine.XR.ARFoundation;

namespace Sitar.Unity
{
    [RequireComponent(typeof(SitarRecorder))]
    public sealed class SitarVenue : MonoBehaviour
    {
        [Header("Anchor")]
        public ARTrackedImageManager trackedImageManager;
        [Tooltip("The reference image's name in the library: the venue's anchor id.")] public string anchorId = "venue-anchor";

        [Header("Venue map")]
        [Tooltip("The venue's map.json (GET /v1/venues/{id}/map.json).")] public TextAsset venueMap;
        [Tooltip("Translucent tile, 1 unit square, local +Y up.")] public GameObject surfaceTilePrefab;
        [Tooltip("Small faint dot of the path trail.")] public GameObject pathDotPrefab;
        public Material tileLow;
        public Material tileMedium;
        public Material tileHigh;
        public Material trail;
        [Tooltip("Shows and hides the venue layer.")] public Button mapToggle;

        [Header("Guidance")]
        public Camera arCamera;
        [Tooltip("An arrow pointing right, under a screen-space overlay canvas.")] public GameObject edgeArrowPrefab;
        public float edgeMarginPx = 60;
        [Tooltip("A marker pulses for this long after it first comes into view.")] public float pulseSeconds = 3;

        SitarRecorder recorder;
        SitarSession venueFor;
        bool mapShown = true;
        bool mapDrawn;
        float nextRedraw;
        readonly List<GameObject> layer = new List<GameObject>();
        readonly List<GameObject> arrows = new List<GameObject>();
        readonly Kineticon kineticon = new Kineticon();
        Guide[] guides = new Guide[16];
        EdgeArrow[] edgeArrows = new EdgeArrow[16];
        VenueCell[] cells = new VenueCell[64];

        void Awake()
        {
            recorder = GetComponent<SitarRecorder>();
            kineticon.PulseSeconds = pulseSeconds;
            if (mapToggle != null) mapToggle.onClick.AddListener(ToggleMap);
        }

        void OnEnable()
        {
            if (trackedImageManager != null) trackedImageManager.trackedImagesChanged += OnTrackedImages;
        }

        void OnDisable()
        {
            if (trackedImageManager != null) trackedImageManager.trackedImagesChanged -= OnTrackedImages;
        }

        /// <summary>Shows or hides the venue map layer.</summary>
        public void ToggleMap()
        {
            mapShown = !mapShown;
            foreach (GameObject g in layer) g.SetActive(mapShown);
        }

        void OnTrackedImages(ARTrackedImagesChangedEventArgs args)
        {
            SitarSession session = recorder.Session;
            if (session == null || !recorder.IsRecording) return;
            foreach (ARTrackedImage image in args.added) Report(session, image);
            foreach (ARTrackedImage image in args.updated) Report(session, image);
        }

        void Report(SitarSession session, ARTrackedImage image)
        {
            if (image.referenceImage.name != anchorId) return;
            Vector3 p = image.transform.position;
            Quaternion q = image.transform.rotation;
            // AR Foundation's TrackingState numbers are the C ABI's: None 0, Limited 1, Tracking 2.
            Tracking tracking = (Tracking)(int)image.trackingState;
            try
            {
                session.Anchor(recorder.LastFrameNs, anchorId, new Pose(p.x, p.y, p.z, q.x, q.y, q.z, q.w), tracking);
            }
            catch (SitarException e)
            {
                Debug.LogWarning("SiTAR anchor: " + e.Message);
            }
        }

        void Update()
        {
            SitarSession session = recorder.Session;
            if (session == null) return;
            if (venueFor != session && venueMap != null)
            {
                venueFor = session;
                mapDrawn = false;
                kineticon.Reset();
                try
                {
                    session.LoadVenue(venueMap.text);
                }
                catch (SitarException e)
                {
                    Debug.LogWarning("SiTAR venue map: " + e.Message);
                }
            }
            // The alignment is refined as observations arrive: redraw the layer each second.
            if (Time.time >= nextRedraw)
            {
                nextRedraw = Time.time + 1;
                DrawLayer(session);
            }
            UpdateGuide(session);
        }

        void DrawLayer(SitarSession session)
        {
            int n;
            try
            {
                n = session.VenueCells(cells);
                if (n > cells.Length)
                {
                    cells = new VenueCell[n];
                    n = session.VenueCells(cells);
                }
            }
            catch (SitarException)
            {
                return; // no venue, or its anchor not fully tracked yet
            }
            foreach (GameObject g in layer) Destroy(g);
            layer.Clear();
            for (int i = 0; i < n; i++)
            {
                VenueCell c = cells[i];
                bool surface = c.Kind == CellKind.Surface;
                GameObject prefab = surface ? surfaceTilePrefab : pathDotPrefab;
                if (prefab == null) continue;
                GameObject g = Instantiate(prefab, new Vector3((float)c.Px, (float)c.Py, (float)c.Pz), Quaternion.identity);
                Material m = surface ? TileMaterial(c.ErrorClass) : trail;
                if (m != null)
                {
                    foreach (Renderer r in g.GetComponentsInChildren<Renderer>()) r.sharedMaterial = m;
                }
                g.SetActive(mapShown);
                layer.Add(g);
            }
            mapDrawn = n > 0;
        }

        Material TileMaterial(ErrorClass c)
        {
            switch (c)
            {
                case ErrorClass.High: return tileHigh;
                case ErrorClass.Medium: return tileMedium;
                default: return tileLow;
            }
        }

        void UpdateGuide(SitarSession session)
        {
            if (arCamera == null) return;
            Vector3 p = arCamera.transform.position;
            Quaternion q = arCamera.transform.rotation;
            var camera = new Pose(p.x, p.y, p.z, q.x, q.y, q.z, q.w);
            int n;
            try
            {
                n = session.Guide(camera, arCamera.fieldOfView, Screen.width, Screen.height, edgeMarginPx, guides);
                if (n > guides.Length)
                {
                    guides = new Guide[n];
                    edgeArrows = new EdgeArrow[n];
                    n = session.Guide(camera, arCamera.fieldOfView, Screen.width, Screen.height, edgeMarginPx, guides);
                }
            }
            catch (SitarException)
            {
                n = 0;
            }
            int shown = VenueView.EdgeArrows(guides, n, Screen.height, edgeArrows);
            while (arrows.Count < shown && edgeArrowPrefab != null)
            {
                arrows.Add(Instantiate(edgeArrowPrefab, Vector3.zero, Quaternion.identity));
            }
            for (int i = 0; i < arrows.Count; i++)
            {
                bool on = i < shown;
                arrows[i].SetActive(on);
                if (!on) continue;
                arrows[i].transform.position = new Vector3(edgeArrows[i].X, edgeArrows[i].Y, 0);
                arrows[i].transform.rotation = Quaternion.Euler(0, 0, edgeArrows[i].RotationDeg);
            }
            // Markers come first in the guide, in SitarRecorder's marker order.
            IReadOnlyList<GameObject> markers = recorder.MarkerObjects;
            for (int i = 0; i < markers.Count && i < n; i++)
            {
                if (markers[i] == null) continue;
                float s = (float)kineticon.Scale(i, guides[i].OnScreen, Time.time);
                markers[i].transform.localScale = new Vector3(s, s, s);
            }
        }

        /// <summary>Whether the venue layer has been drawn (the anchor was fully tracked).</summary>
        public bool MapDrawn { get { return mapDrawn; } }
    }
}
