; TF5200 diagnosis, ID 20223 "Unexpected DEFAULT. Does not match the current control block.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251163531.html
; adapted: the page's ":" line dropped.
; expect: error 20223
N10 G00 X0 Y0 Z0
N20 $DEFAULT
N1000 M30
