// fpp-scanner's page: what the page knows, in one place. Every module reads
// and changes it; the scanner's own state comes from its status and events.

export const page = {
  token: '',
  tokenWorks: false,       // the scanner took page.token at least once
  reachable: true,         // the last request reached the scanner
  lastContact: 0,          // Date.now() of the last answer
  bannerTimer: null,
  state: 'unknown',
  viewer: null,
  eventsGeneration: 0,
  eventsAbort: null,
  scanId: null,            // the scan the progress bar follows
  cloudWanted: null,       // the scan whose cloud the viewer is to show
  finished: new Set(),     // scans whose end the page has shown
  session: '',             // the calibration session shown
  poseId: null,            // the pose being taken
  thumbnails: new Map(),   // pose id -> object URL
  previewTimer: null,
  previewUrl: null,
};
