; TF5200 diagnosis, ID 20244 "Unexpected 'CONTINUE'. No valid/open control blocks.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251254923.html
; adapted: the page's ":" line dropped.
; expect: error 20244
N10   G00 X0 Y0 Z0
N20   $CONTINUE
N1000 M30
