; TF5200 diagnosis, ID 20216 "Unexpected ELSEIF. Does not match the current control block.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251133067.html
; adapted: the page's ":" line dropped.
; expect: error 20216
N10   G00 X0 Y0 Z0
N20   $ELSEIF
N1000 M30
