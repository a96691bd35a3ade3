; TF5200 programming manual, "Global, valid up to end of main program (V.P.)"
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/207966475.html
; adapted: the page's ":" and "; …" lines dropped; G01 F6000 before the move (the page's move has no feed); M30 appended.
; expect: end X=20
#VAR
  V.P.VAR_1                           ;REAL64, 0.0
  V.P.VAR_2 : UNS32 = 200             ;UNS32, 200
  V.P.VAR_3 : REAL64 = 11.34          ;REAL64, 11.34
  V.P.VAR_4 : STRING[20] = "END_OK"   ;STRING, END_OK
  V.P.VAR_5 = 20                      ;REAL64, 20.0
#ENDVAR
G01 F6000
XV.P.VAR_5        ;X20.0
M30
