; TF5200 diagnosis, ID 20020 "Circle centre point parameter outside permissible data format.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250558603.html
; adapted: none.
; expect: error 20020
N10 G00 X0 Y0 Z0
N20 G02 I94967596 F1000
N1000 M30
